#include "rvlio/formats/crs.h"

#include <proj.h>

#include <cmath>
#include <utility>

namespace rvlio {
// Owners of PROJ's handles (named: GeodeticToCrs::Impl holds them).
namespace proj_handles {
struct ContextDeleter {
  void operator()(PJ_CONTEXT* ctx) const { proj_context_destroy(ctx); }
};
struct PjDeleter {
  void operator()(PJ* pj) const { proj_destroy(pj); }
};
}  // namespace proj_handles
using Context = std::unique_ptr<PJ_CONTEXT, proj_handles::ContextDeleter>;
using Pj = std::unique_ptr<PJ, proj_handles::PjDeleter>;

namespace {

// PROJ logs errors to stderr by default; the library never prints.
void Silent(void*, int, const char*) {}

Context NewContext() {
  Context ctx(proj_context_create());
  if (ctx) proj_log_func(ctx.get(), nullptr, Silent);
  return ctx;
}

// PROJ's reason for the last failure in ctx, or `fallback`.
std::string Reason(PJ_CONTEXT* ctx, const char* fallback) {
  const int err = proj_context_errno(ctx);
  const char* text = err != 0 ? proj_context_errno_string(ctx, err) : nullptr;
  return text != nullptr ? text : fallback;
}

bool IsGeographic(PJ_TYPE t) {
  return t == PJ_TYPE_GEOGRAPHIC_CRS || t == PJ_TYPE_GEOGRAPHIC_2D_CRS ||
         t == PJ_TYPE_GEOGRAPHIC_3D_CRS;
}

// The horizontal part of a CRS: the first member of a compound CRS, else itself.
PJ_TYPE HorizontalType(PJ_CONTEXT* ctx, PJ* crs) {
  if (proj_get_type(crs) != PJ_TYPE_COMPOUND_CRS) return proj_get_type(crs);
  Pj horizontal(proj_crs_get_sub_crs(ctx, crs, 0));
  return horizontal ? proj_get_type(horizontal.get()) : PJ_TYPE_UNKNOWN;
}

Status NotACrs(const std::string& crs, const std::string& why) {
  return Status::InvalidInput("survey.crs '" + crs.substr(0, 80) + "': " + why);
}

}  // namespace

bool IsLocalCrs(const std::string& crs) { return crs == "local"; }

StatusOr<Crs> ResolveCrs(const std::string& crs) {
  RVLIO_CHECK_MSG(!IsLocalCrs(crs), "ResolveCrs of local");
  Context ctx = NewContext();
  if (!ctx) return Status::Internal("PROJ: cannot create a context");
  Pj pj(proj_create(ctx.get(), crs.c_str()));
  if (!pj)
    return NotACrs(crs, "unknown coordinate reference system (" +
                            Reason(ctx.get(), "PROJ cannot parse it") +
                            "; e.g. EPSG:25832, a PROJ string or WKT, or local)");
  if (!proj_is_crs(pj.get()))
    return NotACrs(crs, "not a coordinate reference system but an operation (a PROJ string "
                        "names a CRS with +type=crs)");
  const PJ_TYPE horizontal = HorizontalType(ctx.get(), pj.get());
  if (IsGeographic(horizontal))
    return NotACrs(crs, "geographic (degrees); the map is in metres: give a projected CRS "
                        "such as UTM (e.g. EPSG:25832)");
  if (horizontal == PJ_TYPE_VERTICAL_CRS)
    return NotACrs(crs, "a vertical CRS only; give a projected one (optionally compound with it)");
  Crs out;
  out.given = crs;
  const char* name = proj_get_name(pj.get());
  out.name = name != nullptr ? name : "";
  const char* const options[] = {"MULTILINE=NO", nullptr};
  const char* wkt = proj_as_wkt(ctx.get(), pj.get(), PJ_WKT1_GDAL, options);
  if (wkt == nullptr) wkt = proj_as_wkt(ctx.get(), pj.get(), PJ_WKT2_2019, options);
  if (wkt == nullptr) return NotACrs(crs, "PROJ cannot write it as WKT");
  out.wkt = wkt;
  return out;
}

struct GeodeticToCrs::Impl {
  Context ctx;
  Pj transform;
};

GeodeticToCrs::GeodeticToCrs(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
GeodeticToCrs::~GeodeticToCrs() = default;  // Impl destroys the transform before its context
GeodeticToCrs::GeodeticToCrs(GeodeticToCrs&&) noexcept = default;
GeodeticToCrs& GeodeticToCrs::operator=(GeodeticToCrs&&) noexcept = default;

StatusOr<GeodeticToCrs> GeodeticToCrs::Create(const std::string& target_crs) {
  StatusOr<Crs> target = ResolveCrs(target_crs);  // the same checks and messages
  if (!target.ok()) return target.status();
  auto impl = std::make_unique<Impl>();
  impl->ctx = NewContext();
  if (!impl->ctx) return Status::Internal("PROJ: cannot create a context");
  Pj raw(proj_create_crs_to_crs(impl->ctx.get(), "EPSG:4979", target_crs.c_str(), nullptr));
  if (!raw)
    return NotACrs(target_crs, "no transformation from WGS 84 (" +
                                   Reason(impl->ctx.get(), "PROJ found none") + ")");
  // Longitude first, whatever the authority's axis order.
  impl->transform.reset(proj_normalize_for_visualization(impl->ctx.get(), raw.get()));
  if (!impl->transform) return NotACrs(target_crs, "cannot normalize the axis order");
  return GeodeticToCrs(std::move(impl));
}

StatusOr<Eigen::Vector3d> GeodeticToCrs::Transform(double latitude_deg, double longitude_deg,
                                                   double height_m) const {
  const PJ_COORD in = proj_coord(longitude_deg, latitude_deg, height_m, HUGE_VAL);
  proj_errno_reset(impl_->transform.get());
  const PJ_COORD out = proj_trans(impl_->transform.get(), PJ_FWD, in);
  const Eigen::Vector3d p(out.xyz.x, out.xyz.y, out.xyz.z);
  if (proj_errno(impl_->transform.get()) != 0 || !p.allFinite())
    return Status::InvalidInput("cannot transform latitude " + std::to_string(latitude_deg) +
                                ", longitude " + std::to_string(longitude_deg) + " (" +
                                Reason(impl_->ctx.get(), "outside the CRS's area") + ")");
  return p;
}

StatusOr<Eigen::Vector3d> GeodeticToCrs::Inverse(const Eigen::Vector3d& p_crs) const {
  const PJ_COORD in = proj_coord(p_crs.x(), p_crs.y(), p_crs.z(), HUGE_VAL);
  proj_errno_reset(impl_->transform.get());
  const PJ_COORD out = proj_trans(impl_->transform.get(), PJ_INV, in);
  const Eigen::Vector3d lat_lon_h(out.xyz.y, out.xyz.x, out.xyz.z);
  if (proj_errno(impl_->transform.get()) != 0 || !lat_lon_h.allFinite())
    return Status::InvalidInput("cannot transform (" + std::to_string(p_crs.x()) + ", " +
                                std::to_string(p_crs.y()) + ") to latitude, longitude (" +
                                Reason(impl_->ctx.get(), "outside the CRS's area") + ")");
  return lat_lon_h;
}

}  // namespace rvlio
