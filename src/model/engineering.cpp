#include "accelcal/engineering.hpp"

#include <cmath>

#include "accelcal/frame.hpp"

namespace accelcal {

EngineeringParameters ToEngineering(const ModelParameters& params, double gravity) {
  EngineeringParameters eng;
  Mat33 T;
  for (int i = 0; i < 3; ++i) {
    eng.scale_factor(i) = params.K.row(i).norm();
    T.row(i) = params.K.row(i) / eng.scale_factor(i);
  }
  eng.tau_yx = T(1, 0);
  eng.tau_yy = T(1, 1);
  eng.tau_zx = T(2, 0);
  eng.tau_zy = T(2, 1);
  eng.tau_zz = T(2, 2);
  eng.bias_force = params.bias.cwiseQuotient(eng.scale_factor);
  eng.k2_g_per_g2 = gravity * params.k2.cwiseQuotient(eng.scale_factor);
  return eng;
}

ModelParameters FromEngineering(const EngineeringParameters& eng, double gravity) {
  Mat33 T = Mat33::Zero();
  T(0, 0) = 1.0;
  T(1, 0) = eng.tau_yx;
  T(1, 1) = eng.tau_yy;
  T(2, 0) = eng.tau_zx;
  T(2, 1) = eng.tau_zy;
  T(2, 2) = eng.tau_zz;
  ModelParameters params;
  params.K = eng.scale_factor.asDiagonal() * T;
  params.bias = eng.scale_factor.cwiseProduct(eng.bias_force);
  params.k2 = eng.scale_factor.cwiseProduct(eng.k2_g_per_g2) / gravity;
  return params;
}

namespace {

// scale factors (3), misalignment angles (3 or 6), bias (3), k2 (3)
Eigen::VectorXd EngineeringVector(const ModelParameters& params, Frame frame, double gravity) {
  const EngineeringParameters e = ToEngineering(params, gravity);
  const Eigen::VectorXd angles = MisalignmentOf(params.K, frame).rad;
  Eigen::VectorXd v(9 + angles.size());
  v << e.scale_factor, angles, e.bias_force, e.k2_g_per_g2;
  return v;
}

}  // namespace

EngineeringStd EngineeringUncertainty(const ModelParameters& params, ModelKind model, Frame frame,
                                      double gravity, const Eigen::MatrixXd& covariance) {
  const auto& slots = ParameterSlots(model, frame);
  const Eigen::VectorXd theta = Pack(params, slots);
  const Eigen::Index angles = frame == Frame::kPlatform ? 6 : 3;
  Eigen::MatrixXd J(9 + angles, theta.size());
  for (Eigen::Index j = 0; j < theta.size(); ++j) {
    const double h = 1e-6 * std::sqrt(std::max(covariance(j, j), 0.0)) +
                     1e-12 * std::max(1.0, std::abs(theta(j)));
    Eigen::VectorXd plus = theta, minus = theta;
    plus(j) += h;
    minus(j) -= h;
    J.col(j) = (EngineeringVector(Unpack(plus, slots), frame, gravity) -
                EngineeringVector(Unpack(minus, slots), frame, gravity)) /
               (2 * h);
  }
  const Eigen::MatrixXd C = J * covariance * J.transpose();
  const Eigen::VectorXd sd = C.diagonal().cwiseMax(0.0).cwiseSqrt();
  return {sd.head<3>(), sd.segment(3, angles), sd.segment<3>(3 + angles), sd.tail<3>()};
}

}  // namespace accelcal
