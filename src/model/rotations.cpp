// The double instances of rotations.hpp, compiled once.
#include "accelcal/rotations.hpp"

namespace accelcal {

namespace so3 {
template Mat33T<double> Hat(const Vec3T<double>&);
template Vec3T<double> Vee(const Mat33T<double>&);
template Mat33T<double> RightJacobian(const Vec3T<double>&);
template Mat33T<double> RightJacobianInverse(const Vec3T<double>&);
template Mat33T<double> Exp(const Vec3T<double>&, Mat33T<double>*);
template Vec3T<double> Log(const Mat33T<double>&, Mat33T<double>*);
}  // namespace so3
template Mat33T<double> AxisRotation(Axis, const double&, Mat33T<double>*);
template Mat33T<double> IntegrateAngularRate(const std::vector<double>&,
                                             const std::vector<Vec3T<double>>&, RateInterpolation,
                                             const Vec3T<double>&, Mat33T<double>*);

}  // namespace accelcal
