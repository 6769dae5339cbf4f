// The FLU/ENU -> FRD/NED conversions of the example publishers
// (examples/publishers/frames.hpp) against rotation matrices built
// independently with Eigen: R_ned_frd = R_ned_enu * R_enu_flu * R_flu_frd.

#include "../examples/publishers/frames.hpp"

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include <random>

namespace motormix::test {
namespace {

constexpr double kTolerance = 1e-12;

TEST(ExampleFrames, MatchRotationMatrices) {
  Eigen::Matrix3d ned_from_enu;
  ned_from_enu << 0, 1, 0, 1, 0, 0, 0, 0, -1;
  const Eigen::Matrix3d flu_from_frd = Eigen::Vector3d(1, -1, -1).asDiagonal();
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int k = 0; k < 200; ++k) {
    const Eigen::Quaterniond q_in = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized();
    const frames::Quaternion out =
        frames::frd_ned_from_flu_enu({q_in.w(), q_in.x(), q_in.y(), q_in.z()});
    const Eigen::Matrix3d expected = ned_from_enu * q_in.toRotationMatrix() * flu_from_frd;
    const Eigen::Matrix3d got =
        Eigen::Quaterniond(out[0], out[1], out[2], out[3]).toRotationMatrix();
    EXPECT_LT((expected - got).cwiseAbs().maxCoeff(), kTolerance);

    const Eigen::Vector3d v(n(rng), n(rng), n(rng));
    const frames::Vector3 ned = frames::ned_from_enu({v.x(), v.y(), v.z()});
    EXPECT_LT((Eigen::Vector3d(ned[0], ned[1], ned[2]) - ned_from_enu * v).cwiseAbs().maxCoeff(),
              kTolerance);
    const frames::Vector3 frd = frames::frd_from_flu({v.x(), v.y(), v.z()});
    EXPECT_LT((Eigen::Vector3d(frd[0], frd[1], frd[2]) - flu_from_frd.transpose() * v)
                  .cwiseAbs()
                  .maxCoeff(),
              kTolerance);
  }
}

}  // namespace
}  // namespace motormix::test
