#pragma once
// The simulated world: rough bounded surfaces (tunnel walls, floor, ceiling,
// end walls) plus solid boxes and cylinders (features). Ray casting tests
// every surface (a handful) and only the features in the 1-D buckets along
// world x that the ray passes through, nearest bucket first.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "rvlio/sim/geometry.h"

namespace rvlio::sim {

enum class ShapeKind : uint8_t { kFace, kBox, kCylinder };

struct RayHit {
  double range = 0.0;         // m along the unit direction
  float reflectivity = 0.0f;  // of the surface hit, 0..255
  ShapeKind kind = ShapeKind::kFace;
  int index = -1;  // into faces(), boxes() or cylinders()
};

class World {
 public:
  static constexpr size_t kMaxFaces = 32;
  void AddFace(Face face, float reflectivity);
  void AddBox(const Box& box, float reflectivity);
  void AddCylinder(const Cylinder& cylinder, float reflectivity);
  // Adds a raised-cosine patch to the relief of face `index` (a deformation).
  void DeformFace(int index, const HeightField::Bump& bump);
  // Paints the part `area` (face coordinates u, v) of face `index`: a ray
  // that hits the face there returns `reflectivity` (the last paint wins).
  void PaintFace(int index, const Rect2& area, float reflectivity);
  // Builds the feature buckets; call after the last Add*, before Raycast.
  void Finalize(double bucket_size = 1.0);

  // First surface along origin + t dir (dir unit) with 0 < t <= t_max.
  bool Raycast(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_max,
               RayHit* hit) const;
  // Unit normal of the surface `hit` names at the point p on it (world
  // frame; a face's normal points to its +axis, a feature's outwards).
  Eigen::Vector3d Normal(const RayHit& hit, const Eigen::Vector3d& p) const;
  // Distance from p to the nearest surface of any shape (m).
  double DistanceToSurface(const Eigen::Vector3d& p) const;
  // True when p lies inside a box or cylinder.
  bool InsideFeature(const Eigen::Vector3d& p) const;

  const std::vector<Face>& faces() const { return faces_; }
  const std::vector<Box>& boxes() const { return boxes_; }
  const std::vector<Cylinder>& cylinders() const { return cylinders_; }
  // x-extent (m) of features of every kind, for sanity checks.
  std::vector<Eigen::AlignedBox3d> FeatureBounds() const;

 private:
  struct Feature {
    ShapeKind kind;
    int index;
    int first_bucket, last_bucket;
  };
  bool IntersectFeature(const Feature& f, const Ray& ray, double t_max, double* t) const;
  int BucketOf(double x) const;

  struct Paint {
    int face;
    Rect2 area;
    float reflectivity;
  };
  // The reflectivity of face `index` at p (its paint there, else its own).
  float FaceReflectivity(int index, const Eigen::Vector3d& p) const;

  std::vector<Face> faces_;
  std::vector<float> face_reflectivity_;
  std::vector<Paint> paints_;
  std::vector<Box> boxes_;
  std::vector<Cylinder> cylinders_;
  std::vector<float> box_reflectivity_, cylinder_reflectivity_;
  std::vector<Feature> features_;
  std::vector<std::vector<int>> buckets_;  // feature ids per x-interval
  double bucket_x0_ = 0.0, bucket_size_ = 1.0;
  bool finalized_ = false;
};

}  // namespace rvlio::sim
