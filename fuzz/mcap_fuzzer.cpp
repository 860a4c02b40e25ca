// libFuzzer target: the MCAP reader (formats/mcap.h) on arbitrary bytes, through
// Reader::OpenBuffer (the same code path as files). The input is the file.
// An odd-sized input also sets a channel filter (the first channel).
//
// Invariants: no crash, no huge allocation (ASan/rss limits); failures are
// InvalidInput with a one-line message naming the file, and a failing Next()
// keeps returning its error; a file read by the linear scan (no summary)
// returns exactly the messages the scan counted, in log-time order.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "rvlio/formats/mcap.h"

namespace {

[[noreturn]] void Fail(const char* what, const std::string& detail) {
  std::fprintf(stderr, "mcap fuzzer invariant violated: %s\n%s\n", what, detail.c_str());
  std::abort();
}

void CheckError(const rvlio::Status& s) {
  if (s.code() != rvlio::StatusCode::kInvalidInput || s.message().empty())
    Fail("a failure is not InvalidInput with a message", s.message());
  if (s.message().find("'fuzz.mcap'") == std::string::npos)
    Fail("an error does not name the file", s.message());
  if (s.message().find('\n') != std::string::npos) Fail("a multi-line error", s.message());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto reader = rvlio::mcap::Reader::OpenBuffer(
      std::string(reinterpret_cast<const char*>(data), size), "fuzz.mcap");
  if (!reader.ok()) {
    CheckError(reader.status());
    return 0;
  }
  rvlio::mcap::Reader& r = **reader;
  const bool filtered = size % 2 == 1 && !r.channels().empty();
  if (filtered) r.SetChannelFilter({r.channels().begin()->first});
  rvlio::mcap::Message m;
  uint64_t count = 0, last_time = 0;
  for (;;) {
    rvlio::StatusOr<bool> more = r.Next(&m);
    if (!more.ok()) {
      CheckError(more.status());
      rvlio::StatusOr<bool> again = r.Next(&m);
      if (again.ok() || again.status().message() != more.status().message())
        Fail("Next() after an error does not return it again", more.status().message());
      return 0;
    }
    if (!*more) break;
    if (!r.summary().has_summary && count > 0 && m.log_time_ns < last_time)
      Fail("linear scan: messages out of log-time order", "");
    last_time = m.log_time_ns;
    ++count;
  }
  if (!r.summary().has_summary && !filtered && count != r.summary().message_count)
    Fail("linear scan: returned messages differ from the counted ones",
         std::to_string(count) + " vs " + std::to_string(r.summary().message_count));
  return 0;
}
