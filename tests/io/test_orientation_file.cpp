// Orientation files (orientation_file.hpp): the three layouts, the attitude convention as a known
// answer, and every refusal with its line.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "accelcal/error.hpp"
#include "accelcal/orientation_file.hpp"

namespace accelcal {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

TEST(OrientationFile, DirectionsWithOrWithoutHeader) {
  const OrientationFile plain = ParseOrientations("0,0,1\n# a comment\n\n1,0,0\n", "p.csv");
  EXPECT_EQ(plain.layout, OrientationLayout::kDirections);
  ASSERT_EQ(plain.directions.size(), 2u);
  EXPECT_EQ(plain.directions[1], Vec3::UnitX());
  EXPECT_EQ(plain.lines[1], 4u);
  EXPECT_TRUE(plain.attitudes.empty());
  const OrientationFile spaced = ParseOrientations("x y z\n0  -1\t0  # down y\n", "s.txt");
  ASSERT_EQ(spaced.directions.size(), 1u);
  EXPECT_EQ(spaced.directions[0], -Vec3::UnitY());
  // Within 1e-3 of unit length: normalised (a rounded table); further: refused.
  const OrientationFile rounded = ParseOrientations("0.577,0.577,0.577\n", "r.csv");
  EXPECT_NEAR(rounded.directions[0].norm(), 1.0, 1e-15);
}

TEST(OrientationFile, RollPitchYawFollowTheDocumentedConvention) {
  // c = (−sin pitch, sin roll cos pitch, cos roll cos pitch), whatever the yaw.
  const OrientationFile f = ParseOrientations(
      "roll_deg,pitch_deg,yaw_deg\n0,0,0\n90,0,0\n0,90,0\n180,0,37\n23,-41,123\n", "a.csv");
  EXPECT_EQ(f.layout, OrientationLayout::kRollPitchYaw);
  ASSERT_EQ(f.directions.size(), 5u);
  ASSERT_EQ(f.attitudes.size(), 5u);
  EXPECT_LT((f.directions[0] - Vec3::UnitZ()).norm(), 1e-15);
  EXPECT_LT((f.directions[1] - Vec3::UnitY()).norm(), 1e-15);
  EXPECT_LT((f.directions[2] + Vec3::UnitX()).norm(), 1e-15);
  EXPECT_LT((f.directions[3] + Vec3::UnitZ()).norm(), 1e-15);
  const double roll = 23 * kDeg, pitch = -41 * kDeg;
  const Vec3 expected(-std::sin(pitch), std::sin(roll) * std::cos(pitch),
                      std::cos(roll) * std::cos(pitch));
  EXPECT_LT((f.directions[4] - expected).norm(), 1e-15);
  // Yaw optional.
  const OrientationFile two = ParseOrientations("roll_deg pitch_deg\n23 -41\n", "b.txt");
  EXPECT_LT((two.directions[0] - expected).norm(), 1e-15);
}

TEST(OrientationFile, QuaternionsGiveTheSameDirectionsAsTheirAngles) {
  const Eigen::Quaterniond q = AttitudeFromRollPitchYaw(23 * kDeg, -41 * kDeg, 123 * kDeg);
  const std::string text = "qw,qx,qy,qz\n" + std::to_string(q.w()) + "," + std::to_string(q.x()) +
                           "," + std::to_string(q.y()) + "," + std::to_string(q.z()) + "\n";
  const OrientationFile f = ParseOrientations(text, "q.csv");
  EXPECT_EQ(f.layout, OrientationLayout::kQuaternions);
  // std::to_string keeps 6 decimals: the directions agree to that.
  EXPECT_LT((f.directions[0] - UpDirectionInBody(q)).norm(), 1e-5);
  EXPECT_NEAR(f.attitudes[0].norm(), 1.0, 1e-15);
}

TEST(OrientationFile, GimbalAnglesFollowPaper003sChain) {
  // Table 1 rows 2 and 14 (θ in degrees): (0, 45, 0) → (0, ½√2, ½√2), (135, 270, 0) →
  // (−½√2, ½√2, 0).
  const OrientationFile f =
      ParseOrientations("theta1_deg,theta2_deg,theta3_deg\n0,45,0\n135,270,0\n", "g.csv");
  EXPECT_EQ(f.layout, OrientationLayout::kGimbalAngles);
  const double h = std::sqrt(0.5);
  EXPECT_LT((f.directions[0] - Vec3(0, h, h)).norm(), 1e-15);
  EXPECT_LT((f.directions[1] - Vec3(-h, h, 0)).norm(), 1e-15);
  EXPECT_TRUE(f.attitudes.empty());
}

// The InputError of `text`, or a failure when it parses.
InputError ErrorOf(const std::string& text) {
  try {
    ParseOrientations(text, "f.csv");
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "parsed: " << text;
  return InputError("", 0, "");
}

TEST(OrientationFile, RefusesWhatItCannotReadNamingTheLine) {
  EXPECT_EQ(ErrorOf("a,b,c\n0,0,1\n").line(), 1u);
  EXPECT_NE(ErrorOf("a,b,c\n").reason().find("unknown header"), std::string::npos);
  const InputError columns = ErrorOf("x,y,z\n0,0,1\n0,1\n");
  EXPECT_EQ(columns.line(), 3u);
  EXPECT_EQ(columns.reason(), "expected 3 columns, found 2");
  const InputError nan = ErrorOf("0,0,1\nnan,0,1\n");
  EXPECT_EQ(nan.line(), 2u);
  EXPECT_EQ(nan.reason(), "column 1 ('nan') is not a finite number");
  EXPECT_EQ(ErrorOf("0,0,1\n0,2,0\n").reason(),
            "direction 2 (0, 2, 0) is not a unit vector (norm 2)");
  EXPECT_EQ(ErrorOf("qw,qx,qy,qz\n1,0,0,0.1\n").reason(), "quaternion 1 has norm 1.00499, not 1");
  EXPECT_EQ(ErrorOf("# nothing\n\n").reason(), "no orientations in the file");
  EXPECT_EQ(ErrorOf("").line(), 0u);
  EXPECT_EQ(ErrorOf("roll_deg,pitch_deg\n1,2,3\n").line(), 2u);
}

}  // namespace
}  // namespace accelcal
