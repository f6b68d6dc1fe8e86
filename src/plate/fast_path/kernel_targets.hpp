#pragma once
// How the per-configuration solves (section_solve.cpp, continuous_solve.cpp; docs/model.md,
// "Performance") are compiled once per instruction set, for the run-time choice of
// combabc/plate/fast_path/vector_kernels.hpp.
//
// The portable build targets the x86-64 baseline (SSE2: two doubles per vector). Each solve's body
// is compiled twice more, with AVX2 (four doubles per vector) and with AVX-512 (eight), and the
// widest the CPU supports is chosen at run time. No copy fuses a multiply and an add (the solves'
// files are compiled with -ffp-contract=off, src/CMakeLists.txt: AVX-512 implies FMA): a fused
// multiply-add rounds once where the baseline rounds twice. The kernels' arithmetic is element-wise
// in a fixed order (no reassociation, no reductions across vector lanes), so every version gives
// bit-identical results (tested: tests/plate/sensor_model_test.cpp, VectorKernels*). A run's
// history therefore does not depend on the CPU it ran on, only on the build (COMBABC_ARCH, part of
// the version).
//
// COMBABC_KERNEL: the kernels are forced inline, so that each copy of a solve's body runs them
// with its own instruction set (a kernel left out of line would run the baseline's).

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define COMBABC_HAVE_VECTOR_KERNELS 1
#define COMBABC_TARGET_AVX2 __attribute__((target("avx2")))
#define COMBABC_TARGET_AVX512 __attribute__((target("avx512f")))
#else
#define COMBABC_HAVE_VECTOR_KERNELS 0
#define COMBABC_TARGET_AVX2
#define COMBABC_TARGET_AVX512
#endif

#if defined(__GNUC__) || defined(__clang__)
#define COMBABC_KERNEL [[gnu::always_inline]] inline
#define COMBABC_KERNEL_LAMBDA __attribute__((always_inline))
#else
#define COMBABC_KERNEL inline
#define COMBABC_KERNEL_LAMBDA
#endif
