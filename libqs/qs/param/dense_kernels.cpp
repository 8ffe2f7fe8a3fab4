#include "qs/param/dense_kernels.h"

namespace qs::param::dense {

namespace portable {
extern const Kernels table;
}
#if defined(__x86_64__) && defined(QS_DENSE_AVX2)
namespace avx2 {
extern const Kernels table;
}
#endif

const Kernels& portable_kernels() { return portable::table; }

const Kernels* avx2_kernels() {
#if defined(__x86_64__) && defined(QS_DENSE_AVX2)
  static const bool supported = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return supported ? &avx2::table : nullptr;
#else
  return nullptr;
#endif
}

const Kernels& kernels() {
  static const Kernels& best = avx2_kernels() ? *avx2_kernels() : portable_kernels();
  return best;
}

}  // namespace qs::param::dense
