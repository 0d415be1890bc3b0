// The interface between libpd and its PETSc plug-in (time/distributed_solve.cpp loads it through
// core/plugin.hpp; time/distributed_solve_petsc.cpp is the plug-in). Plain C types and MPI's
// communicator only; raise the version whenever anything here changes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <mpi.h>

extern "C" {

/// One rank's rows of the reduced stiffness and what GAMG needs besides (distributed_solve.hpp).
/// The rows are the rank's owned unknowns; rows are numbered rank by rank from first_row.
struct pd_petsc_system {
  MPI_Comm comm;
  std::size_t owned;                ///< rows on this rank
  long long first_row;              ///< the global number of its first row
  const std::size_t* owned_unknown; ///< per row: its local unknown (a row of the CSR below)
  const int* row_offsets;           ///< the local stiffness, CSR over the local unknowns
  const int* columns;               ///< (local unknowns)
  const double* values;
  const std::int32_t* row_of_unknown; ///< per local unknown: its global row (every one has one)
  const double* coordinate;           ///< per row: its unknown's reference coordinate
  int block_size;                     ///< the dimension, or 1 (distributed_solve.cpp)
  double relative_tolerance;
  /// Polled at every iteration on every rank (collective): nonzero ends the solve. May be null.
  int (*stop)(void* context);
  void* stop_context;
};

enum pd_petsc_status { pd_petsc_ok = 0, pd_petsc_stopped = 1, pd_petsc_failed = 2 };

struct pd_petsc_plugin {
  std::uint32_t version; ///< pd_petsc_plugin_version
  /// Assemble and set up the solver (collective); null on failure, with the message in `error`.
  void* (*create)(const pd_petsc_system* system, char* error, std::size_t error_size);
  /// Solve with the right-hand side `b` over the rows into `x` (collective); on pd_petsc_ok,
  /// `reason` is PETSc's KSPConvergedReason (negative: did not converge) and `iterations` the
  /// count. On pd_petsc_failed the message is in `error`.
  int (*solve)(void* solver, const double* b, double* x, int* reason, long long* iterations,
               char* error, std::size_t error_size);
  void (*destroy)(void* solver);
};

/// The plug-in's one exported symbol.
const pd_petsc_plugin* libpd_petsc_plugin();
}

inline constexpr std::uint32_t pd_petsc_plugin_version = 1;
inline constexpr const char* pd_petsc_plugin_module = "libpd_petsc.so";
inline constexpr const char* pd_petsc_plugin_entry = "libpd_petsc_plugin";
