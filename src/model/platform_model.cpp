#include "accelcal/platform_model.hpp"

#include <cmath>

namespace accelcal {

namespace {

constexpr double kPi = 3.14159265358979323846;

Mat33 Rotation(int axis, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  Mat33 R = Mat33::Identity();
  const int i = (axis + 1) % 3, j = (axis + 2) % 3;
  R(i, i) = c;
  R(i, j) = -s;
  R(j, i) = s;
  R(j, j) = c;
  return R;
}

// d R_a(θ)ᵀ / dθ = −[e_a×] R_a(θ)ᵀ... written directly: the derivative of the transpose.
Mat33 RotationTransposeDerivative(int axis, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  Mat33 D = Mat33::Zero();
  const int i = (axis + 1) % 3, j = (axis + 2) % 3;
  // R(θ)ᵀ has (i,i) = c, (i,j) = s, (j,i) = −s, (j,j) = c.
  D(i, i) = -s;
  D(i, j) = c;
  D(j, i) = -c;
  D(j, j) = -s;
  return D;
}

}  // namespace

Vec3 PlatformUp(const Vec3& a, Mat33* jacobian) {
  const Mat33 Rz = Rotation(2, a(0)).transpose(), Rx = Rotation(0, a(1)).transpose(),
              Ry = Rotation(1, a(2)).transpose();
  const Vec3 ez = Vec3::UnitZ();
  if (jacobian != nullptr) {
    jacobian->col(0) = RotationTransposeDerivative(2, a(0)) * Rx * Ry * ez;
    jacobian->col(1) = Rz * RotationTransposeDerivative(0, a(1)) * Ry * ez;
    jacobian->col(2) = Rz * Rx * RotationTransposeDerivative(1, a(2)) * ez;
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
