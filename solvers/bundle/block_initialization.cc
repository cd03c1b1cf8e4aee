#include "solvers/bundle/block_initialization.h"

#include <algorithm>
#include <sstream>

#include "core/units.h"
#include "solvers/bundle/triangulation.h"

namespace photopose {
namespace {

// Marks of image i on points whose coordinates are known now (control points, and tie points
// already intersected), as a resection input.
Status ResectionInputFromKnownPoints(const Block& block, int image, ResectionInput* input) {
  ResectionInputOptions options;
  options.include_tie_points_with_positions = true;
  PHOTOPOSE_RETURN_IF_ERROR(MakeResectionInput(block, image, options, input, nullptr));
  // Initial values only: the camera may not be calibrated yet and intersected points are
  // approximate, so the marks' stated accuracy cannot judge this fit; sigma0 comes from the data
  // (the adjustment then tests every mark with its own accuracy).
  std::fill(input->sigma.begin(), input->sigma.end(), 0.0);
  return Status::Ok();
}

}  // namespace

namespace {

std::string ImagesPart(const BlockInitializationSummary& s) {
  return FormatCount(s.images_given, "image") + " with initial values, " +
         std::to_string(s.images_resected) + " resected, " +
         std::to_string(s.not_oriented.size()) + " not oriented";
}

}  // namespace

std::string BlockInitializationSummary::ImagesReport() const {
  return ImagesPart(*this) + "; " + FormatCount(rounds, "round");
}

std::string BlockInitializationSummary::TiePointsReport() const {
  return FormatCount(points_given, "tie point") + " with coordinates, " +
         std::to_string(points_triangulated) + " intersected, " +
         std::to_string(points_not_triangulated) + " not";
}

std::string BlockInitializationSummary::BriefReport() const {
  return ImagesPart(*this) + "; " + TiePointsReport() + "; " + FormatCount(rounds, "round");
}

namespace {

// Resects every image without orientation that sees enough known points; for each image left,
// why (last_reason). True when an image was oriented.
bool ResectImagesFromKnownPoints(const BlockInitializationOptions& options, Block* block,
                                 std::vector<std::string>* last_reason,
                                 BlockInitializationSummary* summary) {
  bool changed = false;
  for (int i = 0; i < static_cast<int>(block->images.size()); ++i) {
    BlockImage& image = block->images[i];
    if (image.eo) continue;
    ResectionInput input;
    const Status made = ResectionInputFromKnownPoints(*block, i, &input);
    if (!made.ok()) {
      (*last_reason)[i] = made.message();
      continue;
    }
    const int known = static_cast<int>(input.points_in_ground.size());
    if (known < options.min_marks_for_resection) {
      (*last_reason)[i] = "it sees " + std::to_string(known) +
                          " points with known coordinates; resection needs " +
                          std::to_string(options.min_marks_for_resection);
      continue;
    }
    const ResectionResult result = ResectImage(options.resection, input);
    if (!result.success) {
      (*last_reason)[i] = "resection from " + std::to_string(known) +
                          " known points failed: " + result.summary.message;
      continue;
    }
    image.eo = result.eo;
    ++summary->images_resected;
    changed = true;
  }
  return changed;
}

// Intersects every tie point without coordinates seen by two oriented images whose rays meet it
// within options.max_ray_misfit_rad. True when a point was intersected.
bool IntersectTiePoints(const BlockInitializationOptions& options, Block* block,
                        BlockInitializationSummary* summary) {
  TriangulationOptions triangulation;
  triangulation.min_intersection_angle_rad = options.min_intersection_angle_rad;
  MarkSigmaDefaults mark_defaults;
  mark_defaults.pixel_px = options.default_sigma_px;
  mark_defaults.film_um = options.default_sigma_um;
  mark_defaults.film_from_pixel_size = false;
  bool changed = false;
  for (size_t p = 0; p < block->points.size(); ++p) {
    BlockPoint& point = block->points[p];
    if (point.role != PointRole::kTie || point.position_m) continue;
    const std::vector<RayObservation> rays = PointRays(*block, static_cast<int>(p), mark_defaults);
    if (rays.size() < 2) continue;
    TriangulationResult result;
    if (!TriangulatePoint(triangulation, rays, &result).ok()) continue;
    // The RMS angle by which the rays miss the point: whitened residuals times the marks'
    // sigma over the focal length (both in the observation unit of each camera).
    double angle_sum = 0.0;
    for (const RayObservation& ray : rays) {
      const double focal = CameraModelFocal(ray.camera->model, ray.camera->params.data());
      angle_sum += ray.sigma / focal;
    }
    const double misfit_rad = result.rms_whitened * angle_sum / rays.size();
    if (!(misfit_rad <= options.max_ray_misfit_rad)) continue;
    point.position_m = result.point_m;
    ++summary->points_triangulated;
    changed = true;
  }
  return changed;
}

}  // namespace

Status InitializeBlock(const BlockInitializationOptions& options, Block* block,
                       BlockInitializationSummary* summary) {
  *summary = BlockInitializationSummary();
  PHOTOPOSE_RETURN_IF_ERROR(Validate(options.resection, "invalid resection options: "));
  if (!(options.max_ray_misfit_rad > 0.0))
    return Status::Error("max_ray_misfit_rad must be positive");
  if (options.min_marks_for_resection < 3)
    return Status::Error("min_marks_for_resection must be at least 3");
  block->BuildIndex();
  const int num_images = static_cast<int>(block->images.size());
  for (const BlockImage& image : block->images) summary->images_given += image.eo.has_value();
  for (const BlockPoint& point : block->points)
    summary->points_given += point.role == PointRole::kTie && point.position_m.has_value();

  std::vector<std::string> last_reason(num_images);
  for (int round = 0; round < options.max_rounds; ++round) {
    // Both steps every round: images resected from the points known so far, then points
    // intersected from the images oriented so far.
    const bool resected = ResectImagesFromKnownPoints(options, block, &last_reason, summary);
    const bool intersected = IntersectTiePoints(options, block, summary);
    summary->rounds = round + 1;
    if (!resected && !intersected) break;
  }
  for (int i = 0; i < num_images; ++i) {
    if (block->images[i].eo) continue;
    summary->not_oriented.push_back(
        {i, last_reason[i].empty() ? "no initial values and nothing to resect it from"
                                   : last_reason[i]});
  }
  for (const BlockPoint& point : block->points)
    summary->points_not_triangulated += point.role == PointRole::kTie && !point.position_m;
  return Status::Ok();
}

void RemoveImages(const std::vector<std::pair<int, std::string>>& images, Block* block) {
  std::vector<char> remove(block->images.size(), 0);
  for (const auto& [index, reason] : images)
    if (index >= 0 && index < static_cast<int>(remove.size())) remove[index] = 1;
  std::vector<int> new_index(block->images.size(), -1);
  std::vector<BlockImage> kept;
  for (size_t i = 0; i < block->images.size(); ++i) {
    if (remove[i]) continue;
    new_index[i] = static_cast<int>(kept.size());
    kept.push_back(std::move(block->images[i]));
  }
  block->images = std::move(kept);
  std::vector<BlockMark> marks;
  for (BlockMark& mark : block->marks) {
    if (new_index[mark.image] < 0) continue;
    mark.image = new_index[mark.image];
    marks.push_back(std::move(mark));
  }
  block->marks = std::move(marks);
  block->BuildIndex();
}

}  // namespace photopose
