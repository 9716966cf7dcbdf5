#include "accelcal/engineering.hpp"

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

}  // namespace accelcal
