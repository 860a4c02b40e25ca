#pragma once
// Analytic ray intersection for the simulator's world: rough axis-aligned
// surfaces (a plane displaced by a smooth height field), oriented boxes and
// finite cylinders. Rays have unit directions, so the ray parameter t is the
// range in metres. Every shape also gives its distance from a point (used by
// the tests to check that simulated points lie on the surfaces).
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "rvlio/sim/random.h"

namespace rvlio::sim {

struct Ray {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d dir = Eigen::Vector3d::UnitX();  // unit length
};

// Smooth deterministic displacement h(u, v) = sum_k A_k sin(a_k u + b_k v + phi_k)
// + sum_j b_j(u, v) (m): waves plus raised-cosine patches (Bump, a local
// deformation). Its magnitude is bounded by amplitude_bound() = sum |A_k| +
// sum |B_j|, its gradient norm by slope_bound() = sum |A_k| |(a_k, b_k)| + ...
// and its second directional derivative along a unit (u, v) direction by
// curvature_bound() = sum |A_k| |(a_k, b_k)|^2 + ... (the bumps' terms in
// AddBump).
class HeightField {
 public:
  struct Wave {
    double amplitude;  // m
    double ku, kv;     // rad/m
    double phase;      // rad
  };
  // b(u, v) = amplitude c((u - u_center) / u_length) c((v - v_center) / v_length)
  // with c(s) = 0.5 (1 + cos(2 pi s)) for |s| < 1/2, else 0; a length of 0
  // makes c = 1 along that axis (uniform). C1: value and slope vanish at the
  // edge of the patch.
  struct Bump {
    double amplitude = 0.0;          // m, at the centre
    double u_center = 0.0, u_length = 0.0;  // m (length 0: uniform in u)
    double v_center = 0.0, v_length = 0.0;  // m (length 0: uniform in v)
  };
  HeightField() = default;
  explicit HeightField(std::vector<Wave> waves);
  void AddBump(const Bump& bump);
  // `components` waves with random directions, wavelengths log-uniform in
  // [lambda_min, lambda_max], amplitudes proportional to the wavelength
  // (similar slope per wave) and summing to `amplitude`.
  static HeightField Random(Rng& rng, int components, double amplitude, double lambda_min,
                            double lambda_max);

  double Height(double u, double v) const;
  double Height(double u, double v, double* dh_du, double* dh_dv) const;
  double amplitude_bound() const { return amplitude_bound_; }
  double slope_bound() const { return slope_bound_; }
  double curvature_bound() const { return curvature_bound_; }
  bool flat() const { return waves_.empty() && bumps_.empty(); }
  const std::vector<Wave>& waves() const { return waves_; }
  const std::vector<Bump>& bumps() const { return bumps_; }

 private:
  // Adds the bumps' value (and gradient when du, dv are given) to *h.
  void AddBumps(double u, double v, double* h, double* du, double* dv) const;

  std::vector<Wave> waves_;
  std::vector<Bump> bumps_;
  double amplitude_bound_ = 0.0;
  double slope_bound_ = 0.0;
  double curvature_bound_ = 0.0;
};

// Axis-aligned rectangle in the (u, v) coordinates of a face.
struct Rect2 {
  double u_min = 0.0, u_max = 0.0, v_min = 0.0, v_max = 0.0;
  bool Contains(double u, double v) const {
    return u >= u_min && u <= u_max && v >= v_min && v <= v_max;
  }
};

// A bounded rough surface p[axis] = offset + h(p[u], p[v]) where
// (u, v) = (axis + 1, axis + 2) mod 3, for (p[u], p[v]) inside `bounds` and
// outside every hole. Two-sided.
struct Face {
  int axis = 2;
  double offset = 0.0;
  Rect2 bounds;
  std::vector<Rect2> holes;
  HeightField relief;

  int UAxis() const { return (axis + 1) % 3; }
  int VAxis() const { return (axis + 2) % 3; }
  bool Covers(double u, double v) const;
  // The part [t0, t1] of [t_min, t_max] in which the ray is inside the slab
  // |p[axis] - offset| <= amplitude bound that contains the surface.
  bool Slab(const Ray& ray, double t_min, double t_max, double* t0, double* t1) const;
  // The first crossing of the ray with the (unbounded) height field in
  // [t_min, t_max]; true (and *t) when it lies inside the face.
  bool Intersect(const Ray& ray, double t_min, double t_max, double* t) const;
  // |p[axis] - offset - h(p[u], p[v])| where the face covers p, else +inf.
  double Distance(const Eigen::Vector3d& p) const;
  // Unit normal of the height field at (p[u], p[v]): the gradient of
  // p[axis] - offset - h, i.e. e_axis - dh/du e_u - dh/dv e_v normalized
  // (pointing to +axis; the face is two-sided).
  Eigen::Vector3d Normal(const Eigen::Vector3d& p) const;
};

// Box with centre, orientation R_world_box and half extents (m).
struct Box {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Matrix3d R_world_box = Eigen::Matrix3d::Identity();
  Eigen::Vector3d half = Eigen::Vector3d::Constant(0.5);

  // Entry point of the ray in (t_min, t_max]; false for no hit or an origin
  // inside the box.
  bool Intersect(const Ray& ray, double t_min, double t_max, double* t) const;
  double Distance(const Eigen::Vector3d& p) const;  // |signed distance|
  bool Contains(const Eigen::Vector3d& p) const;    // p inside or on the box
  // Outward unit normal of the side nearest p (p on the surface: the side it lies on).
  Eigen::Vector3d Normal(const Eigen::Vector3d& p) const;
  Eigen::AlignedBox3d Bounds() const;
};

// Solid finite cylinder: axis through `center` along unit `axis`, closed by
// two discs at +-half_length.
struct Cylinder {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  double radius = 0.5;
  double half_length = 1.0;

  bool Intersect(const Ray& ray, double t_min, double t_max, double* t) const;
  double Distance(const Eigen::Vector3d& p) const;  // |signed distance|
  bool Contains(const Eigen::Vector3d& p) const;    // p inside or on the cylinder
  // Outward unit normal of the nearest part (mantle or end disc) for p on the surface.
  Eigen::Vector3d Normal(const Eigen::Vector3d& p) const;
  Eigen::AlignedBox3d Bounds() const;
};

}  // namespace rvlio::sim
