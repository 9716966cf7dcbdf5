#include "accelcal/design.hpp"

#include <charconv>
#include <cmath>
#include <stdexcept>

#include "accelcal/simulate.hpp"
#include "solver_common.hpp"

namespace accelcal {

namespace {

// The information matrix of the x-first gauge (12-parameter layout; masked entries identity).
internal::Information Fisher(const internal::Problem& problem, const ModelParameters& device,
                             const std::vector<Vec3>& directions, const Vec3& sigma) {
  const internal::InformationRows rows =
      internal::ReducedInformationRows(problem, device, directions);
  Eigen::VectorXd weight(problem.positions());
  for (int k = 0; k < problem.positions(); ++k) {
    weight(k) = 1.0 / rows.normals[static_cast<std::size_t>(k)].cwiseAbs2().dot(sigma.cwiseAbs2());
  }
  internal::Information info;
  info.reduced = rows.U.transpose() * weight.asDiagonal() * rows.U;
  internal::FinishInformation(problem.model, rows.A_diagonal, &info);
  return info;
}

}  // namespace

PlannedUncertainty PredictUncertainty(const ModelParameters& device, ModelKind model,
                                      double gravity, const std::vector<Vec3>& directions,
                                      const Vec3& sigma_raw) {
  if (!(gravity > 0) || !sigma_raw.allFinite() || !(sigma_raw.minCoeff() > 0)) {
    throw std::invalid_argument("the gravity and the noise must be positive");
  }
  for (const Vec3& c : directions) {
    if (!(std::abs(c.norm() - 1.0) < 1e-6)) {
      throw std::invalid_argument("planned directions must be unit vectors");
    }
  }
  PlannedUncertainty out;
  out.model = model;
  out.frame = FrameOf(device.K);
  // The z-first device is the x-first device of the mirrored problem (frame.hpp).
  const bool mirror = out.frame == Frame::kZFirst;
  ModelParameters x_device = mirror ? MirrorAxes(device) : device;
  if (model == ModelKind::kLinear) x_device.k2.setZero();
  std::vector<Vec3> x_directions = directions;
  if (mirror) {
    for (Vec3& c : x_directions) c = MirrorAxes(c);
  }
  const Vec3 x_sigma = mirror ? MirrorAxes(sigma_raw).cwiseAbs() : sigma_raw;
  const std::vector<Vec3> no_readings(directions.size());
  const internal::Problem problem{no_readings, gravity, model};
  const internal::Information info = Fisher(problem, x_device, x_directions, x_sigma);
  out.rcond = info.rcond;
  out.observable = info.rcond >= internal::kMinInformationRcond;
  if (info.weakest >= 0) {
    out.weakest = std::string(
        ParameterSlots(ModelKind::kQuadratic, out.frame)[static_cast<std::size_t>(info.weakest)]
            .name);
  }
  out.std.K.setZero();
  if (!out.observable) return out;
  const internal::Mat12 inverse = info.Inverse();
  const std::vector<int>& cols = ActiveColumns(model);
  const int P = NumParameters(model);
  out.crlb.resize(P, P);
  for (int i = 0; i < P; ++i) {
    for (int j = 0; j < P; ++j) out.crlb(i, j) = inverse(cols[i], cols[j]);
  }
  if (mirror) {
    const Eigen::VectorXd d = MirrorSigns(model);
    out.crlb = d.asDiagonal() * out.crlb * d.asDiagonal();
  }
  const auto& slots = ParameterSlots(model, out.frame);
  for (std::size_t i = 0; i < slots.size(); ++i) {
    const auto index = static_cast<Eigen::Index>(i);
    const double sd = std::sqrt(std::max(0.0, out.crlb(index, index)));
    switch (slots[i].group) {
      case ParameterGroup::kK:
        out.std.K(slots[i].row, slots[i].col) = sd;
        break;
      case ParameterGroup::kBias:
        out.std.bias(slots[i].row) = sd;
        break;
      case ParameterGroup::kK2:
        out.std.k2(slots[i].row) = sd;
        break;
    }
  }
  return out;
}

std::optional<std::vector<Vec3>> SchemeDirections(std::string_view name) {
  if (name == "yang18") return Yang18Directions();
  if (name == "six") {
    return std::vector<Vec3>{Vec3::UnitX(),  -Vec3::UnitX(), Vec3::UnitY(),
                             -Vec3::UnitY(), Vec3::UnitZ(),  -Vec3::UnitZ()};
  }
  constexpr std::string_view kRandom = "random:";
  if (name.substr(0, kRandom.size()) != kRandom) return std::nullopt;
  std::string_view rest = name.substr(kRandom.size());
  const std::size_t colon = rest.find(':');
  int count = 0;
  std::uint64_t seed = 1;
  const std::string_view count_text = rest.substr(0, colon);
  auto [end, ec] = std::from_chars(count_text.data(), count_text.data() + count_text.size(), count);
  if (ec != std::errc() || end != count_text.data() + count_text.size() || count < 1) {
    return std::nullopt;
  }
  if (colon != std::string_view::npos) {
    const std::string_view seed_text = rest.substr(colon + 1);
    auto [e2, ec2] = std::from_chars(seed_text.data(), seed_text.data() + seed_text.size(), seed);
    if (ec2 != std::errc() || e2 != seed_text.data() + seed_text.size()) return std::nullopt;
  }
  return RandomDirections(count, seed);
}

}  // namespace accelcal
