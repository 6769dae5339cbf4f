#include <motormix/mixing_matrix.hpp>

#include <Eigen/QR>
#include <Eigen/SVD>

namespace motormix {

namespace {
// Singular values below this fraction of the largest are treated as zero.
constexpr double kRankRelativeTolerance = 1e-9;
}  // namespace

EffectivenessMatrix effectiveness_of(const MixingMatrix& mixing) {
  const Eigen::MatrixXd m = mixing;
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(m);
  cod.setThreshold(kRankRelativeTolerance);
  return cod.pseudoInverse();
}

int rank_of(const MixingMatrix& mixing) {
  const Eigen::MatrixXd m = mixing;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(m);
  svd.setThreshold(kRankRelativeTolerance);
  return static_cast<int>(svd.rank());
}

}  // namespace motormix
