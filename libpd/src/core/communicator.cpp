// The serial communicator and what does not depend on MPI.
#include "libpd/core/communicator.hpp"

#include <cstdlib>

namespace pd {

std::size_t HaloPlan::sent_entries() const {
  std::size_t n = 0;
  for (const Peer& p : peers) {
    n += p.send.size();
  }
  return n;
}

namespace {

class SerialCommunicator final : public Communicator {
public:
  int rank() const override { return 0; }
  int size() const override { return 1; }
  void sum(std::span<ExactSum> /*sums*/) const override {}
  double max(double x) const override { return x; }
  double min(double x) const override { return x; }
  std::uint64_t sum(std::uint64_t x) const override { return x; }
  void max(std::span<std::int32_t> /*values*/) const override {}
  void exchange(const HaloPlan& /*plan*/, double* /*values*/,
                std::size_t /*width*/) const override {}
  std::vector<std::string> gather(const std::string& bytes) const override { return {bytes}; }
  std::string broadcast(const std::string& bytes) const override { return bytes; }
  void barrier() const override {}
};

} // namespace

const Communicator& serial_communicator() {
  static const SerialCommunicator serial;
  return serial;
}

} // namespace pd
