#pragma once
// The dense kernels of the supernodal Cholesky's fronts, on column-major blocks given by a
// pointer and a leading dimension. Two builds of the same source: a portable one, and on x86-64
// one for AVX2 with FMA, chosen at run time where the processor has both (about 1.7x faster on
// the large fronts). The two round differently, so factors (and the maps solved with them) are the
// same bits on one machine, not across machines of the two kinds.

namespace qs::param::dense {

struct Kernels {
  /// a (n x n) = L L^T in place, L in its lower triangle. False when a pivot is not positive.
  bool (*cholesky)(double* a, int n, int lda);
  /// b (rows x n) := b L^-T, L the lower triangle of l (n x n).
  void (*solve_right_lower_transposed)(const double* l, int n, int ldl, double* b, int rows, int ldb);
  /// The lower triangle of c (n x n) -= a a^T, a (n x k).
  void (*rank_update)(double* c, int n, int ldc, const double* a, int k, int lda);
  /// c (rows x cols) -= a b^T, a (rows x k), b (cols x k).
  void (*multiply_subtract)(double* c, int rows, int cols, int ldc, const double* a, int lda, const double* b,
                            int ldb, int k);
  const char* name;
};

/// The kernels this processor runs best.
const Kernels& kernels();
/// The portable kernels, and the AVX2 ones (null where not built or not supported): for tests.
const Kernels& portable_kernels();
const Kernels* avx2_kernels();

}  // namespace qs::param::dense
