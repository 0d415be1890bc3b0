// The MPI communicator (built when CMake finds MPI: LIBPD_HAVE_MPI), the MPI session and the
// choice between it and the serial communicator.
#include "libpd/core/communicator.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <stdexcept>

#ifdef LIBPD_HAVE_MPI
#include <mpi.h>
#endif

namespace pd {

#ifdef LIBPD_HAVE_MPI

namespace {

void check(int code, const char* what) {
  if (code != MPI_SUCCESS) {
    throw std::runtime_error(std::string("MPI call failed: ") + what);
  }
}

class MpiCommunicator final : public Communicator {
public:
  explicit MpiCommunicator(MPI_Comm comm) : comm_(comm) {
    check(MPI_Comm_rank(comm_, &rank_), "MPI_Comm_rank");
    check(MPI_Comm_size(comm_, &size_), "MPI_Comm_size");
  }
  int rank() const override { return rank_; }
  int size() const override { return size_; }

  void sum(std::span<ExactSum> sums) const override {
    if (size_ == 1 || sums.empty()) {
      return;
    }
    // Normalised limbs lie in [0, 2^32) (the top one is small and signed), so adding them over
    // any number of ranks below 2^31 is exact in int64: the reduction's order cannot matter.
    std::vector<std::int64_t> limbs;
    std::vector<double> non_finite;
    limbs.reserve(sums.size() * ExactSum::limb_count);
    for (ExactSum& s : sums) {
      s.normalise();
      limbs.insert(limbs.end(), s.limbs().begin(), s.limbs().end());
      non_finite.push_back(s.non_finite());
    }
    check(MPI_Allreduce(MPI_IN_PLACE, limbs.data(), static_cast<int>(limbs.size()), MPI_INT64_T,
                        MPI_SUM, comm_),
          "MPI_Allreduce (exact sums)");
    // inf + (-inf) = NaN and NaN + x = NaN in any order: the non-finite part is order-free too.
    check(MPI_Allreduce(MPI_IN_PLACE, non_finite.data(), static_cast<int>(non_finite.size()),
                        MPI_DOUBLE, MPI_SUM, comm_),
          "MPI_Allreduce (non-finite terms)");
    for (std::size_t k = 0; k < sums.size(); ++k) {
      std::copy_n(limbs.begin() + static_cast<std::ptrdiff_t>(k * ExactSum::limb_count),
                  ExactSum::limb_count, sums[k].limbs().begin());
      sums[k].non_finite() = non_finite[k];
      sums[k].normalise();
    }
  }

  double max(double x) const override { return extremum(x, true); }
  double min(double x) const override { return extremum(x, false); }

  std::uint64_t sum(std::uint64_t x) const override {
    check(MPI_Allreduce(MPI_IN_PLACE, &x, 1, MPI_UINT64_T, MPI_SUM, comm_), "MPI_Allreduce");
    return x;
  }

  void max(std::span<std::int32_t> values) const override {
    check(MPI_Allreduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), MPI_INT32_T,
                        MPI_MAX, comm_),
          "MPI_Allreduce (max)");
  }

  void exchange(const HaloPlan& plan, double* values, std::size_t width) const override {
    if (plan.empty()) {
      return;
    }
    const auto start = std::chrono::steady_clock::now();
    const std::size_t peers = plan.peers.size();
    send_.resize(peers);
    receive_.resize(peers);
    std::vector<MPI_Request> requests(2 * peers);
    for (std::size_t p = 0; p < peers; ++p) {
      const HaloPlan::Peer& peer = plan.peers[p];
      receive_[p].resize(peer.receive.size() * width);
      check(MPI_Irecv(receive_[p].data(), static_cast<int>(receive_[p].size()), MPI_DOUBLE,
                      peer.rank, exchange_tag, comm_, &requests[p]),
            "MPI_Irecv");
    }
    for (std::size_t p = 0; p < peers; ++p) {
      const HaloPlan::Peer& peer = plan.peers[p];
      auto& buffer = send_[p];
      buffer.resize(peer.send.size() * width);
      for (std::size_t e = 0; e < peer.send.size(); ++e) {
        std::copy_n(values + width * peer.send[e], width,
                    buffer.begin() + static_cast<std::ptrdiff_t>(width * e));
      }
      check(MPI_Isend(buffer.data(), static_cast<int>(buffer.size()), MPI_DOUBLE, peer.rank,
                      exchange_tag, comm_, &requests[peers + p]),
            "MPI_Isend");
      halo_bytes_ += buffer.size() * sizeof(double);
    }
    check(MPI_Waitall(static_cast<int>(requests.size()), requests.data(), MPI_STATUSES_IGNORE),
          "MPI_Waitall");
    for (std::size_t p = 0; p < peers; ++p) {
      const HaloPlan::Peer& peer = plan.peers[p];
      for (std::size_t e = 0; e < peer.receive.size(); ++e) {
        std::copy_n(receive_[p].begin() + static_cast<std::ptrdiff_t>(width * e), width,
                    values + width * peer.receive[e]);
      }
    }
    halo_seconds_ +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }

  std::vector<std::string> gather(const std::string& bytes) const override {
    int mine = static_cast<int>(bytes.size());
    std::vector<int> counts(static_cast<std::size_t>(size_));
    check(MPI_Gather(&mine, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, comm_), "MPI_Gather");
    std::vector<int> displacements(counts.size(), 0);
    std::string all;
    if (rank_ == 0) {
      for (std::size_t r = 1; r < counts.size(); ++r) {
        displacements[r] = displacements[r - 1] + counts[r - 1];
      }
      all.resize(static_cast<std::size_t>(displacements.back() + counts.back()));
    }
    check(MPI_Gatherv(bytes.data(), mine, MPI_CHAR, all.data(), counts.data(), displacements.data(),
                      MPI_CHAR, 0, comm_),
          "MPI_Gatherv");
    std::vector<std::string> out;
    if (rank_ == 0) {
      for (std::size_t r = 0; r < counts.size(); ++r) {
        out.push_back(all.substr(static_cast<std::size_t>(displacements[r]),
                                 static_cast<std::size_t>(counts[r])));
      }
    }
    return out;
  }

  std::string broadcast(const std::string& bytes) const override {
    auto n = static_cast<std::uint64_t>(bytes.size());
    check(MPI_Bcast(&n, 1, MPI_UINT64_T, 0, comm_), "MPI_Bcast");
    std::string out = rank_ == 0 ? bytes : std::string(n, '\0');
    check(MPI_Bcast(out.data(), static_cast<int>(n), MPI_CHAR, 0, comm_), "MPI_Bcast");
    return out;
  }

  void barrier() const override { check(MPI_Barrier(comm_), "MPI_Barrier"); }

  const void* native() const override { return &comm_; }

private:
  /// One allreduce: MPI_MAX over {NaN flag, ±x} (the minimum as the maximum of −x), since
  /// MPI_MAX/MIN on NaN is implementation-defined.
  double extremum(double x, bool maximum) const {
    double pair[2] = {std::isnan(x) ? 1.0 : 0.0, std::isnan(x) ? 0.0 : (maximum ? x : -x)};
    check(MPI_Allreduce(MPI_IN_PLACE, pair, 2, MPI_DOUBLE, MPI_MAX, comm_), "MPI_Allreduce");
    if (pair[0] != 0) {
      return std::numeric_limits<double>::quiet_NaN();
    }
    return maximum ? pair[1] : -pair[1];
  }

  static constexpr int exchange_tag = 7301;
  MPI_Comm comm_;
  int rank_ = 0;
  int size_ = 1;
  mutable std::vector<std::vector<double>> send_;
  mutable std::vector<std::vector<double>> receive_;
};

} // namespace

const Communicator& world_communicator() {
  int initialised = 0;
  MPI_Initialized(&initialised);
  if (initialised == 0) {
    return serial_communicator();
  }
  static const MpiCommunicator world(MPI_COMM_WORLD);
  return world;
}

bool mpi_available() {
  return true;
}

namespace {

/// Whether an MPI launcher started this process. A plain `pd run` does not initialise MPI:
/// a singleton MPI_Init costs start-up time, may print transport warnings in containers, and its
/// allocations would read as leaks under the sanitizer build.
bool launched_by_mpi() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_SIZE", "PMI_RANK"}) {
    if (std::getenv(v) != nullptr) {
      return true;
    }
  }
  return false;
}

} // namespace

MpiSession::MpiSession(int& argc, char**& argv) {
  int initialised = 0;
  MPI_Initialized(&initialised);
  if (initialised == 0 && launched_by_mpi()) {
    check(MPI_Init(&argc, &argv), "MPI_Init");
    initialised_ = true;
  }
}

MpiSession::~MpiSession() {
  if (initialised_) {
    MPI_Finalize();
  }
}

void MpiSession::abort(int code) {
  int initialised = 0;
  MPI_Initialized(&initialised);
  if (initialised != 0) {
    int size = 1;
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    if (size > 1) {
      std::fflush(nullptr); // the message said before the abort must not die in a buffer
      MPI_Abort(MPI_COMM_WORLD, code);
    }
  }
  std::exit(code);
}

#else

const Communicator& world_communicator() {
  return serial_communicator();
}

bool mpi_available() {
  return false;
}

MpiSession::MpiSession(int& /*argc*/, char**& /*argv*/) {}

MpiSession::~MpiSession() = default;

void MpiSession::abort(int code) {
  std::exit(code);
}

#endif

} // namespace pd
