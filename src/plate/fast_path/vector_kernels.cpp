#include "combabc/plate/fast_path/vector_kernels.hpp"

#include <initializer_list>

#include "plate/fast_path/kernel_targets.hpp"

namespace combabc::plate {

bool CpuSupports(VectorKernels kernels) {
#if COMBABC_HAVE_VECTOR_KERNELS
  switch (kernels) {
    case VectorKernels::kAvx2:
      return __builtin_cpu_supports("avx2") != 0;
    case VectorKernels::kAvx512:
      return __builtin_cpu_supports("avx512f") != 0;
    case VectorKernels::kAuto:
    case VectorKernels::kPortable:
      return true;
  }
  return false;
#else
  return kernels == VectorKernels::kAuto || kernels == VectorKernels::kPortable;
#endif
}

VectorKernels ResolveKernels(VectorKernels requested) {
  if (requested != VectorKernels::kAuto) return requested;
  for (const VectorKernels k : {VectorKernels::kAvx512, VectorKernels::kAvx2}) {
    if (CpuSupports(k)) return k;
  }
  return VectorKernels::kPortable;
}

}  // namespace combabc::plate
