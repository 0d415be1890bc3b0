// Which BLAS kernels the sparse factorisation runs on (time/sparse_factorisation.cpp: CHOLMOD's
// supernodal Cholesky spends its time in dgemm, its solves in dgemv), and on how many threads.
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

/// Start the program again (execv of /proc/self/exe with `argv`) with the settings that OpenBLAS
/// and libgomp read only while they load, before main, so main calls this first:
///  * OPENBLAS_CORETYPE where openblas_core_for_this_cpu names a kernel set;
///  * OMP_WAIT_POLICY=passive. libgomp's default lets a thread that waits at the end of a
///    parallel region spin for up to 300,000 rounds before it sleeps, and OpenBLAS's OpenMP
///    build (under CHOLMOD) waits the same way between its many small parallel calls. On a
///    machine whose cores are busy with other work a spinning thread takes the time slice the
///    thread it waits for needs: measured on 2 cores at load 4–9, the clamped beam's static
///    solve took 14–18 s with 2 threads against 3 s with 1 (86 s in dpotrf at load 7), and
///    Model A's 300 steps 8–18 s against 1.5–2.2 s. Passive waiting (the thread sleeps at once)
///    brought both within the one-thread time; a short spin (GOMP_SPINCOUNT=10000) did not
///    (beam 4.4–5.6 s). The restarted program removes OMP_WAIT_POLICY again, so the programs it
///    starts see the user's environment.
/// A value the user set (OPENBLAS_CORETYPE, OMP_WAIT_POLICY or GOMP_SPINCOUNT) is kept; where the
/// exec fails, the program runs on as it is. A program that links libpd itself sets
/// OMP_WAIT_POLICY in its environment to the same effect. The stop signals (core/stop_signals.hpp)
/// are blocked across the exec, so that none is lost or fatal meanwhile; the restarted program
/// gets back the ones it had unblocked (pd has them blocked from its first instruction and takes
/// them itself, app/interrupt.hpp; pd-fem leaves them at their default action).
void restart_with_process_settings(char** argv);

/// The part of restart_with_process_settings that gives the restarted program back the stop
/// signals it had unblocked, callable on its own before the libraries' initialisers run (from
/// an ELF .preinit_array function: pd-fem's loading of deal.II and its stack would otherwise hold
/// a SIGTERM for as long as it takes). Idempotent.
void take_back_stop_signals_after_restart();

/// Runs the BLAS on one thread while it lives, and restores the thread counts after. CHOLMOD's
/// supernodal factorisation splits its dense blocks over the BLAS's threads, and Debian's
/// OpenBLAS (the OpenMP build) takes as many as `--threads` gives OpenMP, so the factor's last
/// bits, and everything a set-up derives from it, depended on the thread count: the virtual-fibre
/// disks of elliptic-disk and elliptic-disk-regular differed at 4e-6 and the Griffith failure
/// stresses by up to 7 % between 1 and 2 threads. The fibre arms' balance and relaxation
/// (discretisation/fibre_arms.cpp, fibre_relaxation.cpp) factor once per set-up, so they hold
/// one of these, and so does every CHOLMOD factorisation and solve (time/sparse_factorisation.cpp).
class SerialBlas {
public:
  SerialBlas();
  ~SerialBlas();
  SerialBlas(const SerialBlas&) = delete;
  SerialBlas& operator=(const SerialBlas&) = delete;

private:
  int openmp_threads_ = 0;
  int openblas_threads_ = 0;
};

} // namespace pd
