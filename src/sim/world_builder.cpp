#include "rvlio/sim/world_builder.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Geometry>

#include "rvlio/sim/random.h"

namespace rvlio::sim {

namespace {

constexpr double kFar = 1.0e4;         // m, extent of "unbounded" surfaces
constexpr double kCornerMargin = 0.5;  // m, faces overlap at corners so rough corners stay closed
constexpr double kBackdrop = 8.0;      // m, hall: distance of the walls seen through doorways
constexpr double kSink = 0.1;          // m, objects reach this far into floor/walls (no gaps)
constexpr int kAttempts = 40;

Eigen::Matrix3d RotZ(double yaw) {
  return Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).matrix();
}

class Builder {
 public:
  Builder(const SimWorldOptions& o, const std::vector<Eigen::Vector3d>& path, uint64_t seed)
      : o_(o),
        path_(path),
        L_(MakeLayout(o)),
        shell_rng_(Rng::Stream(seed, 11)),
        feature_rng_(Rng::Stream(seed, 13)) {}

  World Build() {
    AddShell();
    if (o_.layout == "hall") {
      AddPillars();
      if (o_.stairs) AddStairs();
    }
    AddClutter();
    AddSparse();
    world_.Finalize(1.0);
    return std::move(world_);
  }

 private:
  double Amp() const { return o_.roughness_amplitude; }

  Face MakeFace(int axis, double offset, const Rect2& bounds, bool rough) {
    Face f;
    f.axis = axis;
    f.offset = offset;
    f.bounds = bounds;
    if (rough)
      f.relief = HeightField::Random(shell_rng_, o_.roughness_components, Amp(),
                                     o_.roughness_wavelength_min, o_.roughness_wavelength_max);
    return f;
  }

  // Doorways (hall): holes in the four walls, [u, v] in face coordinates.
  std::vector<std::vector<Rect2>> MakeOpenings() {
    std::vector<std::vector<Rect2>> holes(4);  // -y, +y, front (x_entrance), back (x_end)
    const double zf = L_.z_floor;
    for (int k = 0; k < o_.openings; ++k) {
      const int wall = shell_rng_.UniformInt(0, 3);
      const double w = shell_rng_.Uniform(1.5, 3.0), h = shell_rng_.Uniform(2.2, 3.0);
      if (wall < 2) {  // y walls: u = z, v = x
        const double x0 = shell_rng_.Uniform(L_.x_entrance + 1.0, L_.x_end - 1.0 - w);
        holes[wall].push_back({zf - kCornerMargin, zf + h, x0, x0 + w});
      } else {  // x walls: u = y, v = z
        const double lo = L_.y_center - L_.half_width + 1.0;
        const double y0 = shell_rng_.Uniform(lo, lo + 2.0 * L_.half_width - 2.0 - w);
        holes[wall].push_back({y0, y0 + w, zf - kCornerMargin, zf + h});
      }
    }
    return holes;
  }

  void AddShell() {
    const bool hall = o_.layout == "hall";
    const bool open = o_.open_entrance && !hall;
    const bool backdrop = hall && o_.openings > 0;
    const double m = kCornerMargin + 2.0 * Amp();
    const double x0 = L_.x_entrance, x1 = o_.end_wall ? L_.x_end : L_.x_end + kFar;
    const double yc = L_.y_center, hw = L_.half_width, zf = L_.z_floor, zc = L_.z_ceiling;
    const double out = backdrop ? kBackdrop + m : 0.0;  // hall ceiling covers the backdrop
    std::vector<std::vector<Rect2>> holes =
        hall ? MakeOpenings() : std::vector<std::vector<Rect2>>(4);

    // Floor (u = x, v = y): continues outside an open entrance.
    world_.AddFace(
        MakeFace(2, zf,
                 {open ? x0 - kFar : x0 - m - out, x1 + m + out, yc - hw - kFar, yc + hw + kFar},
                 true),
        40.f);
    world_.AddFace(
        MakeFace(2, zc, {x0 - m - out, x1 + m + out, yc - hw - m - out, yc + hw + m + out}, true),
        60.f);
    // Side walls (u = z, v = x).
    for (int side = 0; side < 2; ++side) {
      Face f = MakeFace(1, side == 0 ? yc - hw : yc + hw,
                        {zf - m, zc + m, x0 - (open ? 0.0 : m), x1 + m}, true);
      f.holes = holes[side];
      world_.AddFace(std::move(f), 80.f);
    }
    Deform();
    Paint();
    // Front and back walls (u = y, v = z).
    if (!open) {
      Face f = MakeFace(0, x0, {yc - hw - m, yc + hw + m, zf - m, zc + m}, true);
      f.holes = holes[2];
      world_.AddFace(std::move(f), 80.f);
    }
    if (o_.end_wall) {
      Face f = MakeFace(0, L_.x_end, {yc - hw - m, yc + hw + m, zf - m, zc + m}, true);
      f.holes = holes[3];
      world_.AddFace(std::move(f), 80.f);
    }
    if (backdrop) AddBackdrop(m);
  }

  // world.deformation on the floor (face 0), ceiling (1), right (2, -y) or
  // left (3, +y) wall, in that face's (u, v) coordinates and signed towards
  // the inside. Draws no random number: the rest of the world is unchanged.
  void Deform() {
    const SimDeformationOptions& d = o_.deformation;
    if (d.amplitude == 0.0) return;
    const bool wall = d.surface == "left" || d.surface == "right";
    const int face = d.surface == "floor" ? 0 : d.surface == "ceiling" ? 1
                     : d.surface == "right" ? 2 : 3;
    const bool inside_is_plus = d.surface == "floor" || d.surface == "right";
    HeightField::Bump b;
    b.amplitude = inside_is_plus ? d.amplitude : -d.amplitude;
    if (wall) {  // u = z (height above the floor), v = x
      b.u_center = L_.z_floor + d.across_center;
      b.u_length = d.across_length;
      b.v_center = d.x_center;
      b.v_length = d.length;
    } else {  // u = x, v = y (offset from the centre line)
      b.u_center = d.x_center;
      b.u_length = d.length;
      b.v_center = L_.y_center + d.across_center;
      b.v_length = d.across_length;
    }
    world_.DeformFace(face, b);
  }

  // world.band on the floor (face 0), ceiling (1), right (2) or left (3)
  // wall: the whole surface across, x in [x_min, x_max]. Draws no random
  // number.
  void Paint() {
    const SimBandOptions& b = o_.band;
    if (b.reflectivity <= 0.0 || b.x_max <= b.x_min) return;
    const int face = b.surface == "floor" ? 0 : b.surface == "ceiling" ? 1
                     : b.surface == "right" ? 2 : 3;
    const bool wall = face >= 2;
    Rect2 area{-kFar, kFar, -kFar, kFar};
    if (wall) {  // u = z, v = x
      area.v_min = b.x_min;
      area.v_max = b.x_max;
    } else {  // u = x, v = y
      area.u_min = b.x_min;
      area.u_max = b.x_max;
    }
    world_.PaintFace(face, area, static_cast<float>(b.reflectivity));
  }

  // Flat walls kBackdrop outside the hall, seen through its doorways.
  void AddBackdrop(double m) {
    const double bx0 = L_.x_entrance - kBackdrop, bx1 = L_.x_end + kBackdrop;
    const double by0 = L_.y_center - L_.half_width - kBackdrop,
                 by1 = L_.y_center + L_.half_width + kBackdrop;
    const double zf = L_.z_floor, zc = L_.z_ceiling;
    world_.AddFace(MakeFace(1, by0, {zf - m, zc + m, bx0 - m, bx1 + m}, false), 120.f);
    world_.AddFace(MakeFace(1, by1, {zf - m, zc + m, bx0 - m, bx1 + m}, false), 120.f);
    world_.AddFace(MakeFace(0, bx0, {by0 - m, by1 + m, zf - m, zc + m}, false), 120.f);
    world_.AddFace(MakeFace(0, bx1, {by0 - m, by1 + m, zf - m, zc + m}, false), 120.f);
  }

  double PathDistance(const Eigen::AlignedBox3d& box) const {
    double d = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector3d& p : path_) d = std::min(d, box.exteriorDistance(p));
    return d;
  }
  bool Clear(const Eigen::AlignedBox3d& box) const {
    return PathDistance(box) >= o_.path_clearance;
  }

  float FeatureReflectivity() { return static_cast<float>(feature_rng_.Uniform(90.0, 250.0)); }

  bool TryBox(const Box& b) {
    if (!Clear(b.Bounds())) return false;
    world_.AddBox(b, FeatureReflectivity());
    return true;
  }
  bool TryCylinder(const Cylinder& c) {
    if (!Clear(c.Bounds())) return false;
    world_.AddCylinder(c, FeatureReflectivity());
    return true;
  }

  // A box of half extents `half` resting on the floor (sunk kSink into it).
  Box FloorBox(double x, double y, const Eigen::Vector3d& half, const Eigen::Matrix3d& R) const {
    Box b;
    b.half = half;
    b.R_world_box = R;
    b.center = Eigen::Vector3d(x, y, L_.z_floor - kSink + half.z());
    return b;
  }

  // One clutter object at (x, y): box, pillar, irregular block or a stack.
  bool TryClutter(double x, double y) {
    Rng& r = feature_rng_;
    const double H = L_.z_ceiling - L_.z_floor;
    const int kind = r.UniformInt(0, 99);
    if (kind < 40) {
      const Eigen::Vector3d half(r.Uniform(0.2, 1.0), r.Uniform(0.2, 1.0),
                                 r.Uniform(0.15, std::min(1.25, 0.3 * H)));
      return TryBox(FloorBox(x, y, half, RotZ(r.Uniform(-0.6, 0.6))));
    }
    if (kind < 65) {
      Cylinder c;
      c.radius = r.Uniform(0.15, 0.5);
      const double top =
          r.Uniform(0.0, 1.0) < 0.5 ? L_.z_ceiling + kSink : L_.z_floor + r.Uniform(1.0, 0.7 * H);
      c.half_length = 0.5 * (top - (L_.z_floor - kSink));
      c.center = Eigen::Vector3d(x, y, L_.z_floor - kSink + c.half_length);
      return TryCylinder(c);
    }
    if (kind < 85) {  // irregular block: tilted, partly sunk into the floor
      const Eigen::Vector3d half(r.Uniform(0.3, 1.2), r.Uniform(0.3, 1.2), r.Uniform(0.3, 1.0));
      const Eigen::Matrix3d R =
          (Eigen::AngleAxisd(r.Uniform(-M_PI, M_PI), Eigen::Vector3d::UnitZ()) *
           Eigen::AngleAxisd(r.Uniform(-0.5, 0.5), Eigen::Vector3d::UnitY()) *
           Eigen::AngleAxisd(r.Uniform(-0.5, 0.5), Eigen::Vector3d::UnitX()))
              .matrix();
      Box b = FloorBox(x, y, half, R);
      b.center.z() = L_.z_floor + 0.3 * half.z();
      return TryBox(b);
    }
    // A stack: a base box and a smaller one on top.
    const Eigen::Vector3d base(r.Uniform(0.4, 0.9), r.Uniform(0.4, 0.9), r.Uniform(0.3, 0.6));
    const Eigen::Vector3d top(base.x() * r.Uniform(0.4, 0.8), base.y() * r.Uniform(0.4, 0.8),
                              r.Uniform(0.2, 0.5));
    const Eigen::Matrix3d R = RotZ(r.Uniform(-0.4, 0.4));
    Box b0 = FloorBox(x, y, base, R), b1 = b0;
    b1.half = top;
    b1.R_world_box = R * RotZ(r.Uniform(-0.5, 0.5));
    b1.center.z() = b0.center.z() + base.z() + top.z();
    Eigen::AlignedBox3d both = b0.Bounds();
    both.extend(b1.Bounds());
    if (!Clear(both)) return false;
    world_.AddBox(b0, FeatureReflectivity());
    world_.AddBox(b1, FeatureReflectivity());
    return true;
  }

  void AddClutter() {
    const double x_lo = L_.x_entrance + 0.3, x_hi = std::min(L_.clutter_end, L_.x_end - 0.3);
    if (x_hi <= x_lo) return;
    for (int k = 0; k < o_.clutter_count; ++k) {
      for (int attempt = 0; attempt < kAttempts; ++attempt) {
        const double x = feature_rng_.Uniform(x_lo, x_hi);
        const double y = feature_rng_.Uniform(L_.y_center - L_.half_width + 0.2,
                                              L_.y_center + L_.half_width - 0.2);
        if (TryClutter(x, y)) break;
      }
    }
  }

  // A light on a wall, a beam under the ceiling or a pipe along a wall.
  bool TrySparse(double x) {
    Rng& r = feature_rng_;
    const double H = L_.z_ceiling - L_.z_floor, hw = L_.half_width, yc = L_.y_center;
    const double side = r.Uniform() < 0.5 ? -1.0 : 1.0;
    const int kind = r.UniformInt(0, 2);
    if (kind == 0) {
      Box b;
      b.half = Eigen::Vector3d(0.25, 0.08 + kSink, 0.15);
      b.center = Eigen::Vector3d(x, yc + side * (hw - 0.08), L_.z_floor + r.Uniform(0.5, 0.8) * H);
      return TryBox(b);
    }
    if (kind == 1) {
      Box b;
      b.half = Eigen::Vector3d(0.15, hw + kSink, 0.2 + kSink);
      b.center = Eigen::Vector3d(x, yc, L_.z_ceiling - 0.2);
      return TryBox(b);
    }
    Cylinder c;
    c.axis = Eigen::Vector3d::UnitX();
    c.radius = r.Uniform(0.08, 0.2);
    c.half_length = r.Uniform(1.0, 3.0);
    c.center = Eigen::Vector3d(x, yc + side * (hw - c.radius - 0.1),
                               L_.z_floor + r.Uniform(0.3, 0.85) * H);
    return TryCylinder(c);
  }

  void AddSparse() {
    if (o_.sparse_spacing <= 0.0) return;
    const double x_max = (o_.end_wall ? L_.x_end : L_.x_end + kFar) - 1.0;
    for (double x = L_.clutter_end + 0.5 * o_.sparse_spacing; x < x_max; x += o_.sparse_spacing) {
      const double jitter = feature_rng_.Uniform(-0.2, 0.2) * o_.sparse_spacing;
      for (int attempt = 0; attempt < 5; ++attempt)
        if (TrySparse(std::clamp(x + jitter, L_.clutter_end, x_max))) break;
    }
  }

  // Floor-to-ceiling pillars on a grid (hall).
  void AddPillars() {
    const double s = o_.pillar_spacing;
    if (s <= 0.0) return;
    for (double x = L_.x_entrance + 0.5 * s; x < L_.x_end; x += s)
      for (double y = L_.y_center - L_.half_width + 0.5 * s; y < L_.y_center + L_.half_width;
           y += s) {
        Cylinder c;
        c.radius = 0.35;
        c.half_length = 0.5 * (L_.z_ceiling - L_.z_floor) + kSink;
        c.center = Eigen::Vector3d(x, y, 0.5 * (L_.z_floor + L_.z_ceiling));
        TryCylinder(c);
      }
  }

  // Ten steps of 0.18 m x 0.3 m, 1.5 m wide, along one side wall (hall).
  void AddStairs() {
    for (double side : {1.0, -1.0}) {
      const double x0 = 0.5 * (L_.x_entrance + L_.x_end);
      const double y = L_.y_center + side * (L_.half_width - 0.75);
      std::vector<Box> steps;
      Eigen::AlignedBox3d all;
      for (int i = 0; i < 10; ++i) {
        const double h = 0.18 * (i + 1);
        Box b;
        b.half = Eigen::Vector3d(0.15, 0.75, 0.5 * h + 0.5 * kSink);
        b.center = Eigen::Vector3d(x0 + 0.3 * i, y, L_.z_floor - kSink + b.half.z());
        steps.push_back(b);
        if (i == 0)
          all = b.Bounds();
        else
          all.extend(b.Bounds());
      }
      if (!Clear(all)) continue;
      for (const Box& b : steps) world_.AddBox(b, 150.f);
      return;
    }
  }

  const SimWorldOptions& o_;
  const std::vector<Eigen::Vector3d>& path_;
  WorldLayout L_;
  Rng shell_rng_, feature_rng_;
  World world_;
};

}  // namespace

bool WorldLayout::Inside(const Eigen::Vector3d& p, double margin) const {
  return p.x() >= x_entrance + margin && p.x() <= x_end - margin &&
         std::abs(p.y() - y_center) <= half_width - margin && p.z() >= z_floor + margin &&
         p.z() <= z_ceiling - margin;
}

WorldLayout MakeLayout(const SimWorldOptions& o) {
  WorldLayout L;
  L.x_entrance = -o.start_depth;
  L.x_end = L.x_entrance + o.length;
  L.y_center = -o.start_lateral;
  L.half_width = 0.5 * o.width;
  L.z_floor = -o.start_height;
  L.z_ceiling = L.z_floor + o.height;
  L.clutter_end = L.x_entrance + o.clutter_length;
  return L;
}

World BuildWorld(const SimWorldOptions& options, const std::vector<Eigen::Vector3d>& path,
                 uint64_t seed) {
  return Builder(options, path, seed).Build();
}

}  // namespace rvlio::sim
