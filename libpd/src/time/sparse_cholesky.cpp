#include "libpd/time/sparse_cholesky.hpp"

#include "sparse_factorisation.hpp"

#include <stdexcept>

namespace pd {

SparseCholesky::SparseCholesky(std::size_t size, const std::vector<LowerEntry>& lower)
    : size_(size) {
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(lower.size());
  for (const LowerEntry& e : lower) {
    if (e.row < e.column || e.row >= size) {
      throw std::invalid_argument("SparseCholesky: an entry outside the lower triangle");
    }
    triplets.emplace_back(static_cast<Eigen::Index>(e.row), static_cast<Eigen::Index>(e.column),
                          e.value);
  }
  const auto n = static_cast<Eigen::Index>(size);
  Eigen::SparseMatrix<double> matrix(n, n);
  matrix.setFromTriplets(triplets.begin(), triplets.end());
  factor_ = factorise(matrix, true);
}

SparseCholesky::~SparseCholesky() = default;
SparseCholesky::SparseCholesky(SparseCholesky&&) noexcept = default;
SparseCholesky& SparseCholesky::operator=(SparseCholesky&&) noexcept = default;

std::vector<double> SparseCholesky::solve(std::span<const double> b) const {
  if (b.size() != size_) {
    throw std::invalid_argument("SparseCholesky::solve: the right-hand side has the wrong size");
  }
  const Eigen::VectorXd x =
      factor_->solve(Eigen::Map<const Eigen::VectorXd>(b.data(), static_cast<Eigen::Index>(size_)));
  return {x.data(), x.data() + x.size()};
}

std::string SparseCholesky::name() const {
  return factor_->name();
}

std::size_t SparseCholesky::factor_bytes() const {
  return factor_->factor_bytes();
}

} // namespace pd
