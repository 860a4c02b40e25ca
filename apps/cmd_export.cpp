// `rvlio export --map MAP.pcd --out OUT.las [--crs CRS] [--intensity-range R]`:
// any rvlio map PCD (DATA ascii or binary) into ASPRS LAS 1.4, streamed in
// bounded memory (outputs/map_las.h; docs/outputs.md "map.las").
#include <cstdio>
#include <cstdlib>

#include "cli.h"
#include "commands.h"
#include "interrupt.h"
#include "rvlio/common/text.h"
#include "rvlio/formats/atomic_file.h"
#include "rvlio/outputs/map_las.h"

namespace rvlio::cli {

int CmdExport(int argc, char** argv) {
  CommandSpec spec{
      "export",
      "Converts a map PCD (map.pcd of run, refine or merge; DATA ascii or binary) into an "
      "ASPRS LAS 1.4 file (point format 6, 1 mm coordinates) that survey software opens: "
      "intensity, GPS time and ring where the map has them, every other field as LAS extra "
      "bytes (docs/outputs.md \"map.las\"). The file appears complete or not at all. Exit 2 "
      "naming the file for a missing or corrupt map, an unknown CRS or an unwritable output.",
      {{"map", "MAP.pcd", "the map to convert", true},
       {"out", "OUT.las", "the LAS file to write (replaced when it exists)", true},
       {"crs", "CRS", "coordinate reference system of the map's frame, written into the file: "
                      "EPSG:CODE (e.g. EPSG:25832), a PROJ string, WKT, or local (default: none)"},
       {"intensity-range", "LEVELS",
        "the sensor's intensity range, e.g. 256 for 8 bit (LAS intensity = value x 65536 / "
        "LEVELS); default: from the map's largest intensity"}}};
  Args args;
  if (int rc = Parse(spec, argc, argv, 2, &args); rc != 0) return rc < 0 ? 0 : rc;
  LasExportOptions options;
  options.crs = args.Get("crs", kLocalCrs);
  if (args.Has("intensity-range")) {
    const std::string text = args.Get("intensity-range");
    char* end = nullptr;
    options.intensity_range = std::strtod(text.c_str(), &end);
    if (*end != '\0' || !(options.intensity_range >= 1.0 && options.intensity_range <= 1e12))
      return Fail("export", "--intensity-range '" + text + "' is not a number of levels >= 1");
  }
  InterruptScope interrupts;
  options.stop = [] { return Interrupted(); };  // the first signal: stop between chunks
  const std::string out = args.Get("out");
  SetAbortRemovePath(AtomicTempPath(out));      // a second one: _exit without the temporary

  StatusOr<LasExportResult> r = ExportPointCloudToLas(args.Get("map"), out, options);
  SetAbortRemovePath("");
  if (!r.ok()) return Fail("export", r.status());
  if (r->stopped) {
    std::fprintf(stderr, "rvlio export: stopped by %s; %s not written\n",
                 InterruptSignalName().c_str(), out.c_str());
    return InterruptExitCode();
  }
  for (const std::string& w : r->warnings) std::fprintf(stderr, "rvlio export: warning: %s\n", w.c_str());
  const LasWriteStats& s = r->stats;
  std::printf("rvlio export: %llu points -> %s (intensity: %s, time: %s, ring: %s, extra bytes: %s)\n",
              static_cast<unsigned long long>(s.points), out.c_str(),
              r->intensity_field.empty() ? "none" : r->intensity_field.c_str(),
              r->time_field.empty() ? "none" : r->time_field.c_str(),
              r->ring_field.empty() ? "none" : r->ring_field.c_str(),
              r->extra_fields.empty() ? "none" : Join(r->extra_fields, ",").c_str());
  return 0;
}

}  // namespace rvlio::cli
