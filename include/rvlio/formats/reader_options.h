#pragma once
// How recordings are read (config section `io`): the reading and decoding
// thread of formats/sensor_stream.h and its bounded queue.
#include "rvlio/common/options.h"

namespace rvlio {

struct ReaderOptions {
  bool reader_thread = true;  // read and decode on a thread of its own
  int queue_messages = 64;    // messages decoded ahead of the estimator, at most
  double queue_mb = 256.0;    // MB of decoded scan points ahead of the estimator, at most

  template <class V>
  void Visit(V& v) {
    v.Field("reader_thread", reader_thread,
            Spec().Help("read and decode the recording on a thread of its own, ahead of the "
                        "estimator (outputs are byte-identical with false: inline reading)"));
    v.Field("queue_messages", queue_messages,
            Spec().Range(1, 100000).Help("messages the reader thread may decode ahead"));
    v.Field("queue_mb", queue_mb,
            Spec().Unit("MB").Range(1.0, 100000.0).Help(
                "decoded scan memory the reader thread may hold ahead (at least one scan)"));
  }
  Status Validate() { return ValidateFields(*this, "io"); }
};

}  // namespace rvlio
