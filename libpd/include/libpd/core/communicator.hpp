// The processes a run is split over, and the few collective operations libpd needs of them.
//
// libpd's layers see only this interface, never MPI itself: a run in one process uses the serial
// communicator (every collective is the identity), a run under mpirun the MPI one
// (core/mpi_communicator.cpp, built when CMake finds MPI). Everything that crosses processes is
// here, so that the answer's independence of the process count rests on a short list:
//  - sums are ExactSum (core/exact_sum.hpp): exact, so their grouping over ranks cannot matter;
//  - minima, maxima and logical reductions are exact anyway;
//  - halo exchange copies values, it computes nothing.
#pragma once

#include "libpd/core/exact_sum.hpp"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace pd {

/// Which entries a rank sends to and receives from each neighbouring rank, by local index, and
/// how many values each entry has (3 for a position). Built by discretisation/distribution.hpp.
struct HaloPlan {
  struct Peer {
    int rank = 0;
    std::vector<std::uint32_t> send;    ///< local indices of owned entries the peer holds as halo
    std::vector<std::uint32_t> receive; ///< local indices of this rank's halo entries it owns
  };
  std::vector<Peer> peers; ///< ascending rank

  bool empty() const { return peers.empty(); }
  /// Entries sent per exchange, over all peers.
  std::size_t sent_entries() const;
};

class Communicator {
public:
  virtual ~Communicator() = default;
  virtual int rank() const = 0;
  virtual int size() const = 0;
  bool root() const { return rank() == 0; }

  /// Exact sums over all ranks, in place (every rank gets the total).
  virtual void sum(std::span<ExactSum> sums) const = 0;
  double sum(ExactSum s) const {
    sum(std::span<ExactSum>(&s, 1));
    return s.value();
  }
  virtual double max(double x) const = 0; ///< NaN on any rank gives NaN
  virtual double min(double x) const = 0;
  virtual std::uint64_t sum(std::uint64_t x) const = 0;
  bool any(bool b) const { return sum(std::uint64_t{b ? 1U : 0U}) > 0; }
  /// Element-wise maximum of an integer array over all ranks, in place.
  virtual void max(std::span<std::int32_t> values) const = 0;

  /// Copy `width` values per entry from each entry's owner into the halo copies of the plan.
  /// Counts the bytes sent (halo_bytes()).
  virtual void exchange(const HaloPlan& plan, double* values, std::size_t width) const = 0;
  /// Bytes this rank has sent in exchange() so far, and the seconds it spent there (packing,
  /// waiting and unpacking: what overlapping the exchange with the force loop could hide).
  std::uint64_t halo_bytes() const { return halo_bytes_; }
  double halo_seconds() const { return halo_seconds_; }

  /// Every rank's bytes, concatenated in rank order, on the root (empty elsewhere).
  virtual std::vector<std::string> gather(const std::string& bytes) const = 0;
  /// The root's string on every rank.
  virtual std::string broadcast(const std::string& bytes) const = 0;
  virtual void barrier() const = 0;

  /// The MPI_Comm behind this communicator as an opaque pointer (nullptr for the serial one),
  /// for libraries that take one (Zoltan).
  virtual const void* native() const { return nullptr; }

protected:
  mutable std::uint64_t halo_bytes_ = 0;
  mutable double halo_seconds_ = 0;
};

/// The one-process communicator.
const Communicator& serial_communicator();

/// MPI_COMM_WORLD if libpd was built with MPI and MPI has been initialised (MpiSession), else the
/// serial communicator.
const Communicator& world_communicator();

/// Whether libpd was built with MPI.
bool mpi_available();

/// Initialises MPI for the lifetime of the object (a no-op without MPI); the CLI's main holds one.
class MpiSession {
public:
  MpiSession(int& argc, char**& argv);
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;
  /// Abort every rank: an exception on one rank must not leave the others waiting forever.
  [[noreturn]] static void abort(int code);

private:
  bool initialised_ = false;
};

} // namespace pd
