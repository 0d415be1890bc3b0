// Which BLAS kernels the sparse factorisation runs on (time/sparse_factorisation.cpp: CHOLMOD's
// supernodal Cholesky spends its time in dgemm, its solves in dgemv).
#pragma once

#include <string>

namespace pd {

/// OpenBLAS's kernel set ("Haswell", "SkylakeX", "Prescott", …), or "" when the BLAS linked
/// is not OpenBLAS.
std::string openblas_core();

/// The OPENBLAS_CORETYPE to ask for where OpenBLAS fell back to its SSE3 kernels (Prescott) on a
/// CPU with AVX2 or AVX-512 that it does not recognise, else "". Debian 12's OpenBLAS 0.3.21
/// does this on Intel family 6 models newer than Sapphire Rapids (model 207, Emerald Rapids):
/// the plate's factorisation then takes 4.3 s instead of 1.9 s (Haswell kernels; 1 thread).
std::string openblas_core_for_this_cpu();

/// Where openblas_core_for_this_cpu names a kernel set, start the program again (execv of
/// /proc/self/exe with `argv`) with OPENBLAS_CORETYPE set to it: OpenBLAS reads it only while it
/// loads, before main, so main calls this first. A value the user set is kept; where the exec
/// fails, the program runs on as it is.
void restart_with_this_cpus_blas_kernels(char** argv);

} // namespace pd
