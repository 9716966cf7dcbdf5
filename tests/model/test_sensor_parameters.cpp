// Every sensor's parameters listed alike (sensor_parameters.hpp): the same names, order and
// values as each model's own slots and Pack, and the unit each role gives.
#include "accelcal/sensor_parameters.hpp"

#include <gtest/gtest.h>

namespace accelcal {
namespace {

TEST(SensorParameters, TheAccelerometersAreItsSlotsInEveryFrameAndModel) {
  ModelParameters p;
  p.K << 1.01, 0, 0, 0.02, 0.99, 0, -0.03, 0.04, 1.02;
  p.bias << 0.1, -0.2, 0.3;
  p.k2 << 1e-3, 2e-3, 3e-3;
  for (const ModelKind model : {ModelKind::kLinear, ModelKind::kQuadratic}) {
    for (const Frame frame : {Frame::kXFirst, Frame::kZFirst, Frame::kPlatform}) {
      const std::vector<ParameterSlot>& slots = ParameterSlots(model, frame);
      const Eigen::VectorXd values = Pack(p, slots);
      const std::vector<SensorParameter> list = ListParameters(p, model, frame);
      ASSERT_EQ(list.size(), slots.size());
      for (std::size_t i = 0; i < slots.size(); ++i) {
        EXPECT_EQ(list[i].name, slots[i].name);
        EXPECT_EQ(list[i].value, values(static_cast<Eigen::Index>(i)));
        const ParameterRole role = slots[i].group == ParameterGroup::kK ? ParameterRole::kScale
                                   : slots[i].group == ParameterGroup::kBias
                                       ? ParameterRole::kOffset
                                       : ParameterRole::kSquare;
        EXPECT_EQ(list[i].role, role) << slots[i].name;
      }
    }
  }
}

TEST(SensorParameters, TheGyroscopesAreItsSlots) {
  GyroParameters p;
  p.K << 57, 0.1, 0.2, 0.3, 58, 0.4, 0.5, 0.6, 59;
  p.bias << 1, 2, 3;
  p.G << 0.01, 0.02, 0.03, 0.04, 0.05, 0.06, 0.07, 0.08, 0.09;
  for (const GyroModelKind model : {GyroModelKind::kLinear, GyroModelKind::kGSensitive}) {
    const std::vector<GyroParameterSlot>& slots = GyroParameterSlots(model);
    const Eigen::VectorXd values = Pack(p, model);
    const std::vector<SensorParameter> list = ListParameters(p, model);
    ASSERT_EQ(list.size(), slots.size());
    for (std::size_t i = 0; i < slots.size(); ++i) {
      EXPECT_EQ(list[i].name, slots[i].name);
      EXPECT_EQ(list[i].value, values(static_cast<Eigen::Index>(i)));
      const ParameterRole role = slots[i].group == GyroParameterGroup::kK ? ParameterRole::kScale
                                 : slots[i].group == GyroParameterGroup::kBias
                                     ? ParameterRole::kOffset
                                     : ParameterRole::kCrossSensitivity;
      EXPECT_EQ(list[i].role, role) << slots[i].name;
    }
  }
}

TEST(SensorParameters, EachRoleHasItsUnit) {
  EXPECT_EQ(ParameterUnit(ParameterRole::kScale, "counts", "m/s2", ""), "counts per m/s2");
  EXPECT_EQ(ParameterUnit(ParameterRole::kOffset, "counts", "m/s2", ""), "counts");
  EXPECT_EQ(ParameterUnit(ParameterRole::kSquare, "counts", "g", ""), "counts per (g)^2");
  EXPECT_EQ(ParameterUnit(ParameterRole::kCrossSensitivity, "raw", "rad/s", "m/s2"),
            "raw per m/s2");
}

}  // namespace
}  // namespace accelcal
