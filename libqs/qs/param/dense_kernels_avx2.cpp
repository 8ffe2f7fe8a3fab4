// The dense kernels for AVX2 with FMA (dense_kernels.inc), compiled with -mavx2 -mfma on x86-64
// (libqs/CMakeLists.txt). Eigen is renamed here so that none of its functions, compiled for these
// instructions, can stand in for the portable build's at link time.
#if defined(__AVX2__) && defined(__FMA__)
#define Eigen qs_eigen_avx2
#define QS_DENSE_NAMESPACE avx2
#define QS_DENSE_NAME "avx2"
#include "qs/param/dense_kernels.inc"
#endif
