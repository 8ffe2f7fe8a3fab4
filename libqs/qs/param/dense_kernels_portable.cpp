// The dense kernels for any processor (dense_kernels.inc).
#define QS_DENSE_NAMESPACE portable
#define QS_DENSE_NAME "portable"
#include "qs/param/dense_kernels.inc"
