#pragma once
// The texts report.html is made of, compiled into the tool: the page template,
// its style sheet and script (apps/report/), and three.js with its
// OrbitControls (libjs-three's three.min.js and
// examples/js/controls/OrbitControls.js, found at configure time:
// RVLIO_THREE_JS). Defined in the
// source file cmake/EmbedFiles.cmake generates in the build folder.
#include <string_view>

namespace rvlio::cli::report::assets {

std::string_view ReportTemplate();
std::string_view ReportCss();
std::string_view ReportJs();
std::string_view ThreeJs();
std::string_view ThreeOrbitControls();

}  // namespace rvlio::cli::report::assets
