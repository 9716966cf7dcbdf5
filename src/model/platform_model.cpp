#include "accelcal/platform_model.hpp"

#include <cmath>

#include "accelcal/rotations.hpp"

namespace accelcal {

namespace {

constexpr double kPi = 3.14159265358979323846;

}  // namespace

Vec3 PlatformUp(const Vec3& a, Mat33* jacobian) {
  // R_a(θ)ᵀ and its derivative (dR_a/dθ)ᵀ for each gimbal (rotations.hpp).
  Mat33 dRz, dRx, dRy;
  const Mat33 Rz = AxisRotation(Axis::kZ, a(0), &dRz).transpose(),
              Rx = AxisRotation(Axis::kX, a(1), &dRx).transpose(),
              Ry = AxisRotation(Axis::kY, a(2), &dRy).transpose();
  const Vec3 ez = Vec3::UnitZ();
  if (jacobian != nullptr) {
    jacobian->col(0) = dRz.transpose() * Rx * Ry * ez;
    jacobian->col(1) = Rz * dRx.transpose() * Ry * ez;
    jacobian->col(2) = Rz * Rx * dRy.transpose() * ez;
  }
  return Rz * Rx * Ry * ez;
}

std::vector<Vec3> Wu2018Table1Angles() {
  const double q = kPi / 4;
  // (θ1, θ2, θ3) in multiples of π/4, rows 1-18 (docs/wu2018-table1.md).
  const int rows[18][3] = {{0, 0, 0}, {0, 1, 0},  {0, 2, 0},  {1, 2, 0},  {2, 2, 0},  {2, 1, 0},
                           {2, 4, 0}, {2, 4, -1}, {2, 4, -2}, {3, 4, -2}, {4, 4, -2}, {4, 4, -1},
                           {4, 5, 0}, {3, 6, 0},  {2, 7, 0},  {2, 0, -1}, {1, 0, -2}, {0, 0, -3}};
  std::vector<Vec3> angles;
  for (const auto& r : rows) angles.emplace_back(r[0] * q, r[1] * q, r[2] * q);
  return angles;
}

Mat33 InstallationMatrix(const Eigen::Matrix<double, 6, 1>& b) {
  Mat33 C;
  C << 1.0, b(0), -b(1), -b(2), 1.0, b(3), b(4), -b(5), 1.0;
  return C;
}

Vec3 PlatformOutput(const PlatformAccelerometer& d, const Vec3& f_p) {
  const Vec3 linear = d.s.cwiseProduct(InstallationMatrix(d.beta) * f_p);
  Vec3 deviation = linear;  // f^a − δb
  for (int it = 0; it < 50 && !d.k_nl.isZero(0); ++it) {
    const Vec3 next = linear + d.k_nl.cwiseProduct(deviation.cwiseAbs2());
    const bool done =
        (next - deviation).cwiseAbs().maxCoeff() <= 1e-16 * next.cwiseAbs().maxCoeff();
    deviation = next;
    if (done) break;
  }
  return deviation + d.bias;
}

}  // namespace accelcal
