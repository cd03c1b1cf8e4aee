// libFuzzer harness: ResectImage (solvers/resection/resection.h) on fuzzed numbers, with every solver,
// Jacobian, loss and minimiser. The numbers stay within what the readers and the CLI accept
// (docs/formats.md, "Limits and refusals"): the library must then never crash, never hang, and
// never report success with a pose or covariance that is not finite.
#include <fuzzer/FuzzedDataProvider.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "core/io/tables.h"
#include "solvers/resection/resection.h"

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
  options.refinement.solver = static_cast<PoseSolver>(in.ConsumeIntegralInRange<int>(0, 2));
  options.refinement.jacobian = in.ConsumeBool() ? JacobianType::kAnalytic : JacobianType::kAutodiff;
  options.refinement.loss = static_cast<LossType>(in.ConsumeIntegralInRange<int>(0, 5));
  options.refinement.ceres.minimizer =
      in.ConsumeBool() ? CeresMinimizer::kTinySolver : CeresMinimizer::kProblem;
  // The CLI's ranges: loss scale (0, 1000] standard deviations, confidence [0.5, 1).
  options.refinement.loss_scale = in.ConsumeFloatingPointInRange<double>(1e-3, 1000.0);
  options.test.confidence = in.ConsumeFloatingPointInRange<double>(0.5, 0.999999);
  options.consensus.ransac.seed = in.ConsumeIntegral<uint64_t>();
  options.consensus.ransac.max_trials = 200;  // keeps one input in milliseconds
  options.refinement.ceres.max_iterations = 30;
  options.refinement.taylor.max_iterations = 30;
  options.allow_no_redundancy = in.ConsumeBool();

  ResectionInput input;
  input.raster = "fuzz";
  input.focal_length = in.ConsumeFloatingPointInRange<double>(1.0, kMaxCoordinate);
  const int n = in.ConsumeIntegralInRange<int>(0, 16);
  const bool stated = in.ConsumeBool();
  for (int i = 0; i < n; ++i) {
    input.image_plane.emplace_back(Number(&in, kMaxCoordinate), Number(&in, kMaxCoordinate));
    input.points_in_ground.emplace_back(Number(&in, kMaxCoordinate), Number(&in, kMaxCoordinate),
                                        Number(&in, kMaxCoordinate));
    input.sigma.push_back(stated ? in.ConsumeFloatingPointInRange<double>(1e-3, 1000.0) : 0.0);
    input.observation_units_per_unit.push_back(
        in.ConsumeFloatingPointInRange<double>(kMinPixelSizeUm * 1.001, kMaxPixelSizeUm * 0.999));
    input.units.push_back(MarkUnit::kPixel);
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
    Require(result.residuals.size() == input.image_plane.size());
    Require(result.inliers.size() == input.image_plane.size());
    Require(result.num_inliers >= 4 || options.allow_no_redundancy);
  }
  return 0;
}
