#include "time_range_options.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace rvlio::cli {
namespace {

bool ParseSeconds(const std::string& text, double* value) {
  char* end = nullptr;
  *value = std::strtod(text.c_str(), &end);
  return !text.empty() && *end == '\0' && std::isfinite(*value);
}

}  // namespace

OptionSpec StartOption() {
  return {"start", "S", "skip the first S seconds of the recording (from its first message)",
          false, false};
}
OptionSpec DurationOption() {
  return {"duration", "S", "process S seconds from --start (default: to the end)", false, false};
}

std::string ParseWindow(const Args& args, ReadWindow* window) {
  if (args.Has("start") && (!ParseSeconds(args.Get("start"), &window->start_s) ||
                            window->start_s < 0.0))
    return "--start '" + args.Get("start") + "' is not a number of seconds >= 0";
  if (args.Has("duration") && (!ParseSeconds(args.Get("duration"), &window->duration_s) ||
                               window->duration_s <= 0.0))
    return "--duration '" + args.Get("duration") + "' is not a positive number of seconds";
  return "";
}

}  // namespace rvlio::cli
