// libFuzzer harness: ResectImage (solvers/resection.h) on fuzzed numbers, with every solver,
// Jacobian, loss and minimiser. The numbers stay within what the readers and the CLI accept
// (docs/formats.md, "Limits and refusals"): the library must then never crash, never hang, and
// never report success with a pose or covariance that is not finite.
#include <fuzzer/FuzzedDataProvider.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "core/tables.h"
#include "solvers/resection.h"

namespace {

void Require(bool condition) {
  if (!condition) std::abort();
}

// A number of magnitude up to `limit`, at a fuzzed scale: small scenes and absurd ones.
double Number(FuzzedDataProvider* in, double limit) {
  static constexpr double kScales[] = {1.0, 1e2, 1e4, 1e6};
  const double scale = std::min(limit, kScales[in->ConsumeIntegralInRange<int>(0, 3)]);
  return in->ConsumeFloatingPointInRange<double>(-scale, scale);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FuzzedDataProvider in(data, size);
  using namespace photopose;
  ResectionOptions options;
  options.solver = static_cast<PoseSolver>(in.ConsumeIntegralInRange<int>(0, 2));
  options.jacobian = in.ConsumeBool() ? JacobianType::kAnalytic : JacobianType::kAutodiff;
  options.loss = static_cast<LossType>(in.ConsumeIntegralInRange<int>(0, 5));
  options.minimizer = in.ConsumeBool() ? CeresMinimizer::kTinySolver : CeresMinimizer::kProblem;
  // The CLI's ranges: (0, 1000] px.
  options.loss_scale_px = in.ConsumeFloatingPointInRange<double>(1e-3, 1000.0);
  options.ransac_threshold_px = in.ConsumeFloatingPointInRange<double>(1e-3, 1000.0);
  options.ransac.seed = in.ConsumeIntegral<uint64_t>();
  options.ransac.max_trials = 200;  // keeps one input in milliseconds
  options.max_iterations = 30;

  ResectionInput input;
  input.raster = "fuzz";
  input.focal_length_um = in.ConsumeFloatingPointInRange<double>(1.0, kMaxCoordinate);
  input.pixel_size_um =
      in.ConsumeFloatingPointInRange<double>(kMinPixelSizeUm * 1.001, kMaxPixelSizeUm * 0.999);
  const int n = in.ConsumeIntegralInRange<int>(0, 16);
  for (int i = 0; i < n; ++i) {
    input.image_plane_um.emplace_back(Number(&in, kMaxCoordinate), Number(&in, kMaxCoordinate));
    input.points_in_ground.emplace_back(Number(&in, kMaxCoordinate), Number(&in, kMaxCoordinate),
                                        Number(&in, kMaxCoordinate));
    input.sigma_px.push_back(in.ConsumeFloatingPointInRange<double>(1e-3, 1000.0));
    input.point_ids.push_back("P" + std::to_string(i));
  }
  if (in.ConsumeBool()) {
    ExteriorOrientation eo;
    eo.set_center_in_ground(
        {Number(&in, kMaxCoordinate), Number(&in, kMaxCoordinate), Number(&in, kMaxCoordinate)});
    eo.set_angles_seed_rad({Number(&in, 7.0), Number(&in, 7.0), Number(&in, 7.0)});
    input.approximate = eo;
  }

  const ResectionResult result = ResectImage(options, input);
  if (result.success) {
    Require(result.eo.parameters.allFinite());
    Require(result.covariance.allFinite());
    Require(std::isfinite(result.sigma0) && result.sigma0 >= 0.0);
    Require(result.residuals_px.size() == input.image_plane_um.size());
    Require(result.inliers.size() == input.image_plane_um.size());
  }
  return 0;
}
