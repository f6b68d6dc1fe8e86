#pragma once
// The instruction set of the fast paths' per-configuration solves (SensorOptions::vector_kernels;
// docs/model.md, "Vector kernels chosen at run time"). Each solve is compiled for the build's own
// instruction set and again for AVX2 and AVX-512, and picked at run time. Every copy gives
// bit-identical results (no fused multiply-adds, the same operations in the same order; tested),
// so the choice changes only the speed, never a run's history.

namespace combabc::plate {

// kAuto, the widest this CPU supports (AVX-512, AVX2, else the build's own); kPortable, the
// build's own; kAvx2 / kAvx512, that one (invalid where the CPU lacks it).
enum class VectorKernels { kAuto, kPortable, kAvx2, kAvx512 };

// Whether this CPU and its operating system support the kernels' instruction set (kAuto and
// kPortable always).
bool CpuSupports(VectorKernels kernels);

// The instruction set the solves run: kAuto resolved to the widest the CPU supports.
VectorKernels ResolveKernels(VectorKernels requested);

}  // namespace combabc::plate
