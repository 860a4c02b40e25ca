#include "rvlio/sim/world.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "rvlio/common/check.h"

namespace rvlio::sim {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
}  // namespace

void World::AddFace(Face face, float reflectivity) {
  RVLIO_CHECK_MSG(faces_.size() < kMaxFaces, "too many faces for the ray caster");
  faces_.push_back(std::move(face));
  face_reflectivity_.push_back(reflectivity);
  finalized_ = false;
}

void World::AddBox(const Box& box, float reflectivity) {
  boxes_.push_back(box);
  box_reflectivity_.push_back(reflectivity);
  features_.push_back({ShapeKind::kBox, static_cast<int>(boxes_.size()) - 1, 0, 0});
  finalized_ = false;
}

void World::AddCylinder(const Cylinder& cylinder, float reflectivity) {
  cylinders_.push_back(cylinder);
  cylinder_reflectivity_.push_back(reflectivity);
  features_.push_back({ShapeKind::kCylinder, static_cast<int>(cylinders_.size()) - 1, 0, 0});
  finalized_ = false;
}

void World::DeformFace(int index, const HeightField::Bump& bump) {
  RVLIO_CHECK(index >= 0 && static_cast<size_t>(index) < faces_.size());
  faces_[static_cast<size_t>(index)].relief.AddBump(bump);
}

void World::PaintFace(int index, const Rect2& area, float reflectivity) {
  RVLIO_CHECK(index >= 0 && static_cast<size_t>(index) < faces_.size());
  paints_.push_back({index, area, reflectivity});
}

float World::FaceReflectivity(int index, const Eigen::Vector3d& p) const {
  float r = face_reflectivity_[static_cast<size_t>(index)];
  for (const Paint& paint : paints_) {
    if (paint.face != index) continue;
    const Face& f = faces_[static_cast<size_t>(index)];
    if (paint.area.Contains(p[f.UAxis()], p[f.VAxis()])) r = paint.reflectivity;
  }
  return r;
}

std::vector<Eigen::AlignedBox3d> World::FeatureBounds() const {
  std::vector<Eigen::AlignedBox3d> out;
  for (const Feature& f : features_)
    out.push_back(f.kind == ShapeKind::kBox ? boxes_[f.index].Bounds()
                                            : cylinders_[f.index].Bounds());
  return out;
}

int World::BucketOf(double x) const {
  const double i = std::floor((x - bucket_x0_) / bucket_size_);
  const double last = static_cast<double>(buckets_.size()) - 1.0;
  return static_cast<int>(std::clamp(i, 0.0, last));
}

void World::Finalize(double bucket_size) {
  RVLIO_CHECK(bucket_size > 0.0);
  const std::vector<Eigen::AlignedBox3d> bounds = FeatureBounds();
  double x_min = 0.0, x_max = 0.0;
  for (size_t i = 0; i < bounds.size(); ++i) {
    x_min = i == 0 ? bounds[i].min().x() : std::min(x_min, bounds[i].min().x());
    x_max = i == 0 ? bounds[i].max().x() : std::max(x_max, bounds[i].max().x());
  }
  bucket_x0_ = x_min;
  bucket_size_ = bucket_size;
  const int count = std::max(1, static_cast<int>(std::ceil((x_max - x_min) / bucket_size)) + 1);
  buckets_.assign(static_cast<size_t>(count), {});
  for (size_t i = 0; i < features_.size(); ++i) {
    Feature& f = features_[i];
    f.first_bucket = BucketOf(bounds[i].min().x());
    f.last_bucket = BucketOf(bounds[i].max().x());
    for (int b = f.first_bucket; b <= f.last_bucket; ++b)
      buckets_[static_cast<size_t>(b)].push_back(static_cast<int>(i));
  }
  finalized_ = true;
}

bool World::IntersectFeature(const Feature& f, const Ray& ray, double t_max, double* t) const {
  return f.kind == ShapeKind::kBox ? boxes_[f.index].Intersect(ray, 0.0, t_max, t)
                                   : cylinders_[f.index].Intersect(ray, 0.0, t_max, t);
}

bool World::Raycast(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_max,
                    RayHit* hit) const {
  RVLIO_CHECK(finalized_);
  const Ray ray{origin, dir};
  double best = t_max;
  bool found = false;
  // Faces in the order the ray reaches their slabs; a slab that starts beyond
  // the best hit cannot hold a nearer one.
  std::pair<double, int> order[kMaxFaces];
  size_t n = 0;
  for (size_t i = 0; i < faces_.size(); ++i) {
    double t0 = 0.0, t1 = 0.0;
    if (!faces_[i].Slab(ray, 1e-9, t_max, &t0, &t1)) continue;
    order[n++] = {t0, static_cast<int>(i)};
  }
  std::sort(order, order + n);
  for (size_t k = 0; k < n && order[k].first <= best; ++k) {
    const int i = order[k].second;
    double t = 0.0;
    if (faces_[static_cast<size_t>(i)].Intersect(ray, 1e-9, best, &t)) {
      best = t;
      found = true;
      *hit = {t, 0.0f, ShapeKind::kFace, i};
    }
  }
  if (found) hit->reflectivity = FaceReflectivity(hit->index, origin + best * dir);
  if (features_.empty()) return found;
  // Walk the buckets from the origin's in the direction of travel; stop when
  // the next bucket starts beyond the best hit so far. A feature that spans
  // several buckets is tested once: in the start bucket or where the walk
  // first reaches it.
  const int start = BucketOf(origin.x());
  const int step = dir.x() >= 0.0 ? 1 : -1;
  const int count = static_cast<int>(buckets_.size());
  for (int b = start; b >= 0 && b < count; b += step) {
    if (b != start) {
      if (std::abs(dir.x()) < 1e-12) break;
      const double boundary = bucket_x0_ + bucket_size_ * (step > 0 ? b : b + 1);
      if ((boundary - origin.x()) / dir.x() > best) break;
    }
    for (int id : buckets_[static_cast<size_t>(b)]) {
      const Feature& f = features_[static_cast<size_t>(id)];
      if (b != start && (step > 0 ? f.first_bucket : f.last_bucket) != b) continue;
      double t = 0.0;
      if (IntersectFeature(f, ray, best, &t)) {
        best = t;
        found = true;
        const float refl = f.kind == ShapeKind::kBox ? box_reflectivity_[f.index]
                                                     : cylinder_reflectivity_[f.index];
        *hit = {t, refl, f.kind, f.index};
      }
    }
  }
  return found;
}

Eigen::Vector3d World::Normal(const RayHit& hit, const Eigen::Vector3d& p) const {
  const size_t i = static_cast<size_t>(hit.index);
  switch (hit.kind) {
    case ShapeKind::kFace: return faces_[i].Normal(p);
    case ShapeKind::kBox: return boxes_[i].Normal(p);
    case ShapeKind::kCylinder: return cylinders_[i].Normal(p);
  }
  return Eigen::Vector3d::Zero();
}

double World::DistanceToSurface(const Eigen::Vector3d& p) const {
  double d = kInf;
  for (const Face& f : faces_) d = std::min(d, f.Distance(p));
  for (const Box& b : boxes_) d = std::min(d, b.Distance(p));
  for (const Cylinder& c : cylinders_) d = std::min(d, c.Distance(p));
  return d;
}

bool World::InsideFeature(const Eigen::Vector3d& p) const {
  for (const Box& b : boxes_)
    if (b.Contains(p)) return true;
  for (const Cylinder& c : cylinders_)
    if (c.Contains(p)) return true;
  return false;
}

}  // namespace rvlio::sim
