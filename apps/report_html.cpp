#include "report_html.h"

#include <string_view>
#include <utility>

#include "report_assets.h"
#include "rvlio/common/check.h"
#include "rvlio/formats/atomic_file.h"
#include "rvlio/version.h"

namespace rvlio::cli::report {
namespace {

std::string EscapeHtml(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

// JSON inside <script>: "</" would end the element early; "<\/" is the same
// JSON string.
std::string ScriptSafeJson(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (size_t i = 0; i < text.size(); ++i) {
    out += text[i];
    if (text[i] == '<' && i + 1 < text.size() && text[i + 1] == '/') out += '\\';
  }
  return out;
}

}  // namespace

std::string RenderReportHtml(const experiments::report::ReportModel& model) {
  const std::string_view page = assets::ReportTemplate();
  const std::string data = ScriptSafeJson(model.json);
  const std::string generator = std::string("rvlio ") + RVLIO_VERSION;
  const std::string title = EscapeHtml(model.title);
  // The markers in the order they appear in the template.
  const std::pair<std::string_view, std::string_view> fills[] = {
      {"@RVLIO_GENERATOR@", generator}, {"@RVLIO_TITLE@", title},
      {"@RVLIO_CSS@", assets::ReportCss()}, {"@RVLIO_DATA@", data},
      {"@RVLIO_THREE@", assets::ThreeJs()},
      {"@RVLIO_THREE_CONTROLS@", assets::ThreeOrbitControls()},
      {"@RVLIO_JS@", assets::ReportJs()}};
  std::string out;
  size_t size = page.size();
  for (const auto& fill : fills) size += fill.second.size();
  out.reserve(size);
  size_t from = 0;
  for (const auto& [marker, text] : fills) {
    const size_t at = page.find(marker, from);
    RVLIO_CHECK(at != std::string_view::npos);  // the template is compiled in
    out.append(page.substr(from, at - from));
    out.append(text);
    from = at + marker.size();
  }
  out.append(page.substr(from));
  return out;
}

StatusOr<WrittenReport> WriteReport(const std::string& dir, const std::string& out_path,
                                    const ReportOptions& options) {
  StatusOr<experiments::report::ReportModel> model = experiments::report::BuildReport(dir, options);
  if (!model.ok()) return model.status();
  WrittenReport written;
  written.path = out_path.empty() ? dir + "/report.html" : out_path;
  const std::string page = RenderReportHtml(*model);
  written.bytes = page.size();
  if (Status s = WriteFileAtomically(written.path, page); !s.ok()) return s;
  return written;
}

}  // namespace rvlio::cli::report
