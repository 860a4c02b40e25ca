#include "rvlio/sim/geometry.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace rvlio::sim {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kRootTol = 1e-9;  // m, |g| at which a surface root is accepted
constexpr int kMaxSteps = 100000;  // sphere-tracing steps (grazing rays on steep relief need many)

// g(t) = (o_w + t r_w - offset) - h(o_u + t r_u, o_v + t r_v): signed height of
// the ray point above the rough surface; its roots are the crossings.
struct SurfaceFunction {
  const Face& face;
  double ow, rw, ou, ru, ov, rv;

  double operator()(double t) const {
    return ow + t * rw - face.offset - face.relief.Height(ou + t * ru, ov + t * rv);
  }
  double WithSlope(double t, double* dg_dt) const {
    double hu = 0.0, hv = 0.0;
    const double h = face.relief.Height(ou + t * ru, ov + t * rv, &hu, &hv);
    *dg_dt = rw - hu * ru - hv * rv;
    return ow + t * rw - face.offset - h;
  }
};

// Safeguarded Newton/bisection from `t` on a bracket [a, b] with g(a), g(b)
// of opposite signs (sa = sign of g(a)).
double RefineBracket(const SurfaceFunction& g, double a, double b, double sa, double t) {
  if (!(t > a && t < b)) t = 0.5 * (a + b);
  for (int i = 0; i < 60; ++i) {
    double slope = 0.0;
    const double value = g.WithSlope(t, &slope);
    if (std::abs(value) < kRootTol || b - a < 1e-12) return t;
    if ((value > 0) == (sa > 0))
      a = t;
    else
      b = t;
    const double newton = slope != 0.0 ? t - value / slope : kInf;
    t = (newton > a && newton < b) ? newton : 0.5 * (a + b);
  }
  return t;
}

// First root of g in [t0, t1] for any ray (also grazing ones that may dip
// under a crest and come out again). Every step is provably shorter than the
// distance to the next root: with G = sign * g > 0, |g'| <= L and |g''| <= K,
//   G(t + d) >= G(t) - L d                      (Lipschitz)
//   G(t + d) >= G(t) + G'(t) d - K d^2 / 2      (Taylor with the curvature bound)
// so G stays positive for d < max(G / L, (G' + sqrt(G'^2 + 2 K G)) / K). The
// second bound makes the steps Newton-like near a transversal crossing
// (quadratic convergence); the march stops within kRootTol of the surface,
// still on the ray's side of it.
bool FirstRoot(const SurfaceFunction& g, double lipschitz, double curvature, double t0, double t1,
               double* root) {
  double t = t0;
  double slope = 0.0;
  double value = g.WithSlope(t, &slope);
  const double sign = value >= 0 ? 1.0 : -1.0;
  for (int i = 0; i < kMaxSteps; ++i) {
    const double G = sign * value, dG = sign * slope;
    if (G < kRootTol) {
      *root = t;
      return true;
    }
    double step = G / lipschitz;
    if (curvature > 0.0) {
      step = std::max(step, (dG + std::sqrt(dG * dG + 2.0 * curvature * G)) / curvature);
    } else if (dG < 0.0) {
      step = std::max(step, G / -dG);
    }
    if (t >= t1) return false;
    t = std::min(t + step, t1);
    value = g.WithSlope(t, &slope);
    if (sign * value < 0.0) {  // only reachable through rounding at a root
      *root = t;
      return true;
    }
  }
  return false;
}

// The only root of g in [t0, t1] when g is strictly monotonic (the ray is
// steeper than any surface slope, |r_w| > slope_bound |r_uv|): Newton from the
// crossing of the mean plane, safeguarded by the bracket. At an unclipped
// slab boundary the sign of g is known (|h| <= amplitude bound), so g is only
// evaluated at ends clipped by [t_min, t_max].
bool MonotonicRoot(const SurfaceFunction& g, double t0, double t1, bool clipped0, bool clipped1,
                   double* root) {
  const double entry_sign = g.rw > 0 ? -1.0 : 1.0;
  double s0 = entry_sign;
  if (clipped0) {
    const double g0 = g(t0);
    if (std::abs(g0) < kRootTol) {
      *root = t0;
      return true;
    }
    s0 = g0 >= 0 ? 1.0 : -1.0;
    if (s0 != entry_sign) return false;  // already beyond the only root
  }
  if (clipped1) {
    const double g1 = g(t1);
    if (std::abs(g1) < kRootTol) {
      *root = t1;
      return true;
    }
    if ((g1 >= 0 ? 1.0 : -1.0) == s0) return false;  // the root lies beyond t1
  }
  *root = RefineBracket(g, t0, t1, s0, (g.face.offset - g.ow) / g.rw);
  return true;
}

// sin and cos of x (|x| < 1e6) to ~1e-15: Cody-Waite reduction to
// |r| <= pi/4 and Taylor polynomials. The height field is *defined* by this
// function (ray casting and distances use the same one), so it need not match
// libm bit for bit; it is about three times faster than std::sin + std::cos.
inline void SinCos(double x, double* s, double* c) {
  constexpr double kTwoOverPi = 0.63661977236758134308;
  constexpr double kP1 = 1.570796325802803;  // pi/2 in three 30-bit parts
  constexpr double kP2 = 9.920935791635221e-10;
  constexpr double kP3 = 5.170182981794105e-19;
  const double q = std::floor(x * kTwoOverPi + 0.5);
  const double r = ((x - q * kP1) - q * kP2) - q * kP3;
  const double r2 = r * r;
  const double sr =
      r * (1.0 +
           r2 * (-1.0 / 6 +
                 r2 * (1.0 / 120 +
                       r2 * (-1.0 / 5040 +
                             r2 * (1.0 / 362880 + r2 * (-1.0 / 39916800 +
                                                        r2 * (1.0 / 6227020800.0 +
                                                              r2 * (-1.0 / 1307674368000.0))))))));
  const double cr =
      1.0 +
      r2 * (-0.5 + r2 * (1.0 / 24 +
                         r2 * (-1.0 / 720 +
                               r2 * (1.0 / 40320 +
                                     r2 * (-1.0 / 3628800 + r2 * (1.0 / 479001600 +
                                                                  r2 * (-1.0 / 87178291200.0)))))));
  switch (static_cast<int64_t>(q) & 3) {
    case 0:
      *s = sr;
      *c = cr;
      break;
    case 1:
      *s = cr;
      *c = -sr;
      break;
    case 2:
      *s = -sr;
      *c = -cr;
      break;
    default:
      *s = -cr;
      *c = sr;
      break;
  }
}

}  // namespace

HeightField::HeightField(std::vector<Wave> waves) : waves_(std::move(waves)) {
  for (const Wave& w : waves_) {
    amplitude_bound_ += std::abs(w.amplitude);
    slope_bound_ += std::abs(w.amplitude) * std::hypot(w.ku, w.kv);
    curvature_bound_ += std::abs(w.amplitude) * (w.ku * w.ku + w.kv * w.kv);
  }
}

namespace {
// c(s) = 0.5 (1 + cos(2 pi s)) on |s| < 1/2 (else 0) of s = (x - center) /
// length, and its derivative with respect to x; length 0: c = 1.
double RaisedCosine(double x, double center, double length, double* dc_dx) {
  *dc_dx = 0.0;
  if (length <= 0.0) return 1.0;
  const double s = (x - center) / length;
  if (std::abs(s) >= 0.5) return 0.0;
  *dc_dx = -M_PI / length * std::sin(2.0 * M_PI * s);
  return 0.5 * (1.0 + std::cos(2.0 * M_PI * s));
}
// Largest |c'| and |c''| of the raised cosine of that length (0: uniform).
double RaisedCosineSlope(double length) { return length > 0.0 ? M_PI / length : 0.0; }
double RaisedCosineCurvature(double length) {
  return length > 0.0 ? 2.0 * M_PI * M_PI / (length * length) : 0.0;
}
}  // namespace

void HeightField::AddBump(const Bump& bump) {
  bumps_.push_back(bump);
  const double a = std::abs(bump.amplitude);
  const double su = RaisedCosineSlope(bump.u_length), sv = RaisedCosineSlope(bump.v_length);
  amplitude_bound_ += a;
  slope_bound_ += a * std::hypot(su, sv);
  // Along a unit direction (p, q): p^2 b_uu + 2 p q b_uv + q^2 b_vv, with
  // |2 p q| <= 1 and p^2, q^2 <= 1.
  curvature_bound_ += a * (RaisedCosineCurvature(bump.u_length) +
                           RaisedCosineCurvature(bump.v_length) + su * sv);
}

void HeightField::AddBumps(double u, double v, double* h, double* du, double* dv) const {
  for (const Bump& b : bumps_) {
    double cu_du = 0.0, cv_dv = 0.0;
    const double cu = RaisedCosine(u, b.u_center, b.u_length, &cu_du);
    const double cv = RaisedCosine(v, b.v_center, b.v_length, &cv_dv);
    *h += b.amplitude * cu * cv;
    if (du != nullptr) *du += b.amplitude * cu_du * cv;
    if (dv != nullptr) *dv += b.amplitude * cu * cv_dv;
  }
}

HeightField HeightField::Random(Rng& rng, int components, double amplitude, double lambda_min,
                                double lambda_max) {
  if (components <= 0 || amplitude <= 0.0) return HeightField();
  std::vector<double> lambdas(static_cast<size_t>(components));
  double sum = 0.0;
  for (double& l : lambdas) {
    l = lambda_min * std::pow(lambda_max / lambda_min, rng.Uniform());
    sum += l;
  }
  std::vector<Wave> waves;
  for (double l : lambdas) {
    const double dir = rng.Uniform(0.0, 2.0 * M_PI);
    const double k = 2.0 * M_PI / l;
    waves.push_back(
        {amplitude * l / sum, k * std::cos(dir), k * std::sin(dir), rng.Uniform(0.0, 2.0 * M_PI)});
  }
  return HeightField(std::move(waves));
}

double HeightField::Height(double u, double v) const {
  double h = 0.0;
  for (const Wave& w : waves_) {
    double s = 0.0, c = 0.0;
    SinCos(w.ku * u + w.kv * v + w.phase, &s, &c);
    h += w.amplitude * s;
  }
  AddBumps(u, v, &h, nullptr, nullptr);
  return h;
}

double HeightField::Height(double u, double v, double* dh_du, double* dh_dv) const {
  double h = 0.0, hu = 0.0, hv = 0.0;
  for (const Wave& w : waves_) {
    const double arg = w.ku * u + w.kv * v + w.phase;
    double s = 0.0, c = 0.0;
    SinCos(arg, &s, &c);
    h += w.amplitude * s;
    hu += w.amplitude * w.ku * c;
    hv += w.amplitude * w.kv * c;
  }
  AddBumps(u, v, &h, &hu, &hv);
  *dh_du = hu;
  *dh_dv = hv;
  return h;
}

bool Face::Covers(double u, double v) const {
  if (!bounds.Contains(u, v)) return false;
  for (const Rect2& h : holes)
    if (h.Contains(u, v)) return false;
  return true;
}

bool Face::Slab(const Ray& ray, double t_min, double t_max, double* t0, double* t1) const {
  const double amp = relief.amplitude_bound(), ow = ray.origin[axis], rw = ray.dir[axis];
  *t0 = t_min;
  *t1 = t_max;
  if (std::abs(rw) < 1e-15) return amp > 0.0 && std::abs(ow - offset) <= amp;
  const double ta = (offset - amp - ow) / rw, tb = (offset + amp - ow) / rw;
  *t0 = std::max(t_min, std::min(ta, tb));
  *t1 = std::min(t_max, std::max(ta, tb));
  return *t0 <= *t1;
}

bool Face::Intersect(const Ray& ray, double t_min, double t_max, double* t) const {
  const SurfaceFunction g{*this,
                          ray.origin[axis],
                          ray.dir[axis],
                          ray.origin[UAxis()],
                          ray.dir[UAxis()],
                          ray.origin[VAxis()],
                          ray.dir[VAxis()]};
  double t0 = 0.0, t1 = 0.0;
  if (!Slab(ray, t_min, t_max, &t0, &t1)) return false;
  double root = 0.0;
  if (relief.flat()) {
    root = (offset - g.ow) / g.rw;
  } else {
    const double slope_rate = relief.slope_bound() * std::hypot(g.ru, g.rv);
    if (std::abs(g.rw) > 1.001 * slope_rate) {
      if (!MonotonicRoot(g, t0, t1, t0 == t_min, t1 == t_max, &root)) return false;
    } else if (!FirstRoot(g, std::abs(g.rw) + slope_rate,
                          relief.curvature_bound() * (g.ru * g.ru + g.rv * g.rv), t0, t1, &root)) {
      return false;
    }
  }
  if (root < t_min || root > t_max) return false;
  if (!Covers(g.ou + root * g.ru, g.ov + root * g.rv)) return false;
  *t = root;
  return true;
}

double Face::Distance(const Eigen::Vector3d& p) const {
  const double u = p[UAxis()], v = p[VAxis()];
  if (!Covers(u, v)) return kInf;
  return std::abs(p[axis] - offset - relief.Height(u, v));
}

Eigen::Vector3d Face::Normal(const Eigen::Vector3d& p) const {
  double dh_du = 0.0, dh_dv = 0.0;
  relief.Height(p[UAxis()], p[VAxis()], &dh_du, &dh_dv);
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  n[axis] = 1.0;
  n[UAxis()] = -dh_du;
  n[VAxis()] = -dh_dv;
  return n.normalized();
}

bool Box::Intersect(const Ray& ray, double t_min, double t_max, double* t) const {
  const Eigen::Vector3d o = R_world_box.transpose() * (ray.origin - center);
  const Eigen::Vector3d d = R_world_box.transpose() * ray.dir;
  double t_near = -kInf, t_far = kInf;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d[i]) < 1e-15) {
      if (std::abs(o[i]) > half[i]) return false;
      continue;
    }
    double ta = (-half[i] - o[i]) / d[i], tb = (half[i] - o[i]) / d[i];
    if (ta > tb) std::swap(ta, tb);
    t_near = std::max(t_near, ta);
    t_far = std::min(t_far, tb);
    if (t_near > t_far) return false;
  }
  if (t_near <= 0.0 || t_near < t_min || t_near > t_max) return false;
  *t = t_near;
  return true;
}

double Box::Distance(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d q = (R_world_box.transpose() * (p - center)).cwiseAbs() - half;
  const double outside = q.cwiseMax(0.0).norm();
  const double inside = std::min(q.maxCoeff(), 0.0);
  return std::abs(outside + inside);
}

bool Box::Contains(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d q = (R_world_box.transpose() * (p - center)).cwiseAbs() - half;
  return q.maxCoeff() <= 0.0;
}

Eigen::Vector3d Box::Normal(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d local = R_world_box.transpose() * (p - center);
  int side = 0;
  (local.cwiseAbs() - half).maxCoeff(&side);  // the side p is on: distance ~0, the others < 0
  Eigen::Vector3d n_box = Eigen::Vector3d::Zero();
  n_box[side] = local[side] < 0.0 ? -1.0 : 1.0;
  return R_world_box * n_box;
}

Eigen::AlignedBox3d Box::Bounds() const {
  const Eigen::Vector3d extent = R_world_box.cwiseAbs() * half;
  return Eigen::AlignedBox3d(center - extent, center + extent);
}

bool Cylinder::Intersect(const Ray& ray, double t_min, double t_max, double* t) const {
  const Eigen::Vector3d w = ray.origin - center;
  const double wa = w.dot(axis), da = ray.dir.dot(axis);
  const Eigen::Vector3d wp = w - wa * axis, dp = ray.dir - da * axis;
  if (wp.squaredNorm() < radius * radius && std::abs(wa) < half_length) return false;  // inside
  double best = kInf;
  // Side: |wp + t dp|^2 = r^2, entering root.
  const double A = dp.squaredNorm(), B = wp.dot(dp), C = wp.squaredNorm() - radius * radius;
  if (A > 1e-18) {
    const double disc = B * B - A * C;
    if (disc >= 0.0) {
      const double ts = (-B - std::sqrt(disc)) / A;
      if (ts > 0.0 && std::abs(wa + ts * da) <= half_length) best = ts;
    }
  }
  // Caps at axial coordinate +-half_length.
  if (std::abs(da) > 1e-15) {
    for (double s : {-half_length, half_length}) {
      const double tc = (s - wa) / da;
      if (tc > 0.0 && tc < best && (wp + tc * dp).squaredNorm() <= radius * radius) best = tc;
    }
  }
  if (best < t_min || best > t_max) return false;
  *t = best;
  return true;
}

double Cylinder::Distance(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d w = p - center;
  const double wa = w.dot(axis);
  const double dr = (w - wa * axis).norm() - radius, dz = std::abs(wa) - half_length;
  const double outside = std::hypot(std::max(dr, 0.0), std::max(dz, 0.0));
  const double inside = std::min(std::max(dr, dz), 0.0);
  return std::abs(outside + inside);
}

bool Cylinder::Contains(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d w = p - center;
  const double wa = w.dot(axis);
  return std::abs(wa) <= half_length && (w - wa * axis).squaredNorm() <= radius * radius;
}

Eigen::Vector3d Cylinder::Normal(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d w = p - center;
  const double wa = w.dot(axis);
  const Eigen::Vector3d radial = w - wa * axis;
  const double dr = radial.norm() - radius, dz = std::abs(wa) - half_length;
  // On an end disc dz ~ 0 and dr <= 0; on the mantle dr ~ 0 and dz <= 0.
  if (dz > dr || radial.norm() < 1e-12) return wa < 0.0 ? Eigen::Vector3d(-axis) : axis;
  return radial / radial.norm();
}

Eigen::AlignedBox3d Cylinder::Bounds() const {
  Eigen::Vector3d extent;
  for (int i = 0; i < 3; ++i)
    extent[i] = std::abs(axis[i]) * half_length +
                radius * std::sqrt(std::max(0.0, 1.0 - axis[i] * axis[i]));
  return Eigen::AlignedBox3d(center - extent, center + extent);
}

}  // namespace rvlio::sim
