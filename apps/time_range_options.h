#pragma once
// --start / --duration of run, refine and compare: a time window of the
// recording (formats/sensor_stream.h).
#include <string>

#include "cli.h"
#include "rvlio/formats/sensor_stream.h"

namespace rvlio::cli {

OptionSpec StartOption();
OptionSpec DurationOption();
// Fills *window from --start / --duration; "" or the error message.
std::string ParseWindow(const Args& args, ReadWindow* window);

}  // namespace rvlio::cli
