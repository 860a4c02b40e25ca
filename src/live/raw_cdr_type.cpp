// The raw CDR type of raw_cdr_type.h: Cyclone DDS's sertype / serdata
// interfaces (dds/ddsi/ddsi_sertype.h, ddsi_serdata.h) over a byte vector.
// A sample is only ever its serialized form: received fragments are copied
// into the vector, written samples are the vector. The typed-sample entry
// points (used by dds_read / dds_write, which this project does not call:
// it uses dds_takecdr / dds_writecdr) take a std::vector<uint8_t>.
#include "raw_cdr_type.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <new>

#include <dds/dds.h>
#include <dds/ddsi/ddsi_serdata.h>
#include <dds/ddsi/ddsi_sertype.h>
#include <dds/ddsi/q_radmin.h>

namespace rvlio::live_detail {
namespace {

using Bytes = std::vector<uint8_t>;

// serdata first: Cyclone hands back the ddsi_serdata pointer.
struct RawSample {
  ddsi_serdata base;
  Bytes bytes;
};

RawSample* AsRaw(ddsi_serdata* d) { return reinterpret_cast<RawSample*>(d); }
const RawSample* AsRaw(const ddsi_serdata* d) { return reinterpret_cast<const RawSample*>(d); }

RawSample* NewSample(const ddsi_sertype* type, ddsi_serdata_kind kind) {
  auto* s = new RawSample();
  ddsi_serdata_init(&s->base, type, kind);
  s->base.hash = type != nullptr ? type->serdata_basehash : 0;
  return s;
}

// --- serdata operations ---

bool EqKey(const ddsi_serdata*, const ddsi_serdata*) { return true; }  // keyless

uint32_t Size(const ddsi_serdata* d) { return static_cast<uint32_t>(AsRaw(d)->bytes.size()); }

void FreeSample(ddsi_serdata* d) { delete AsRaw(d); }

// The received fragments (they may overlap) copied into one payload of `size` bytes.
ddsi_serdata* FromSer(const ddsi_sertype* type, ddsi_serdata_kind kind, const nn_rdata* frag,
                      size_t size) {
  RawSample* s = NewSample(type, kind);
  s->bytes.resize(size);
  uint32_t done = 0;
  for (; frag != nullptr && done < size; frag = frag->nextfrag) {
    if (frag->maxp1 <= done) continue;
    const unsigned char* payload =
        NN_RMSG_PAYLOADOFF(frag->rmsg, NN_RDATA_PAYLOAD_OFF(frag)) + (done - frag->min);
    const uint32_t end = std::min<uint32_t>(frag->maxp1, static_cast<uint32_t>(size));
    std::memcpy(s->bytes.data() + done, payload, end - done);
    done = end;
  }
  s->bytes.resize(done);
  return &s->base;
}

ddsi_serdata* FromSerIov(const ddsi_sertype* type, ddsi_serdata_kind kind, ddsrt_msg_iovlen_t niov,
                         const ddsrt_iovec_t* iov, size_t size) {
  RawSample* s = NewSample(type, kind);
  s->bytes.reserve(size);
  for (ddsrt_msg_iovlen_t i = 0; i < niov; ++i) {
    const auto* p = static_cast<const uint8_t*>(iov[i].iov_base);
    s->bytes.insert(s->bytes.end(), p, p + iov[i].iov_len);
  }
  s->bytes.resize(std::min(s->bytes.size(), size));
  return &s->base;
}

ddsi_serdata* FromKeyhash(const ddsi_sertype* type, const ddsi_keyhash*) {
  return &NewSample(type, SDK_KEY)->base;
}

ddsi_serdata* FromSample(const ddsi_sertype* type, ddsi_serdata_kind kind, const void* sample) {
  RawSample* s = NewSample(type, kind);
  if (kind == SDK_DATA) s->bytes = *static_cast<const Bytes*>(sample);
  return &s->base;
}

void ToSer(const ddsi_serdata* d, size_t off, size_t sz, void* buf) {
  const Bytes& b = AsRaw(d)->bytes;
  const size_t n = off < b.size() ? std::min(sz, b.size() - off) : 0;
  if (n > 0) std::memcpy(buf, b.data() + off, n);
  if (n < sz) std::memset(static_cast<uint8_t*>(buf) + n, 0, sz - n);  // padding to 4
}

ddsi_serdata* ToSerRef(const ddsi_serdata* d, size_t off, size_t sz, ddsrt_iovec_t* ref) {
  ref->iov_base = const_cast<uint8_t*>(AsRaw(d)->bytes.data()) + off;
  ref->iov_len = static_cast<ddsrt_iov_len_t>(sz);
  return ddsi_serdata_ref(d);
}

void ToSerUnref(ddsi_serdata* d, const ddsrt_iovec_t*) { ddsi_serdata_unref(d); }

bool ToSample(const ddsi_serdata* d, void* sample, void**, void*) {
  if (d->kind == SDK_DATA) *static_cast<Bytes*>(sample) = AsRaw(d)->bytes;
  return true;
}

ddsi_serdata* ToUntyped(const ddsi_serdata* d) {
  RawSample* s = NewSample(d->type, SDK_KEY);
  s->base.type = nullptr;  // untyped: the key only, and a keyless type has none
  return &s->base;
}

bool UntypedToSample(const ddsi_sertype*, const ddsi_serdata*, void*, void**, void*) {
  return true;
}

size_t Print(const ddsi_sertype*, const ddsi_serdata* d, char* buf, size_t size) {
  return static_cast<size_t>(std::snprintf(buf, size, "(%zu bytes of CDR)", AsRaw(d)->bytes.size()));
}

void GetKeyhash(const ddsi_serdata*, ddsi_keyhash* buf, bool) {
  std::memset(buf->value, 0, sizeof(buf->value));
}

const ddsi_serdata_ops kSampleOps = [] {
  ddsi_serdata_ops ops{};
  ops.eqkey = EqKey;
  ops.get_size = Size;
  ops.from_ser = FromSer;
  ops.from_ser_iov = FromSerIov;
  ops.from_keyhash = FromKeyhash;
  ops.from_sample = FromSample;
  ops.to_ser = ToSer;
  ops.to_ser_ref = ToSerRef;
  ops.to_ser_unref = ToSerUnref;
  ops.to_sample = ToSample;
  ops.to_untyped = ToUntyped;
  ops.untyped_to_sample = UntypedToSample;
  ops.free = FreeSample;
  ops.print = Print;
  ops.get_keyhash = GetKeyhash;
  return ops;
}();

// --- sertype operations (samples are std::vector<uint8_t>) ---

void FreeType(ddsi_sertype* t) {
  ddsi_sertype_fini(t);
  delete t;
}

void ZeroSamples(const ddsi_sertype*, void* samples, size_t count) {
  auto* v = static_cast<Bytes*>(samples);
  for (size_t i = 0; i < count; ++i) v[i].clear();
}

// Typed sample arrays are not used (dds_takecdr / dds_writecdr only): Cyclone
// calls these for loans, which this project does not take.
void ReallocSamples(void** ptrs, const ddsi_sertype*, void*, size_t, size_t count) {
  for (size_t i = 0; i < count; ++i) ptrs[i] = nullptr;
}

void FreeSamples(const ddsi_sertype*, void**, size_t, dds_free_op_t) {}

bool EqualTypes(const ddsi_sertype*, const ddsi_sertype*) { return true; }  // by name and ops

uint32_t HashType(const ddsi_sertype*) { return 0; }

size_t SerializedSize(const ddsi_sertype*, const void* sample) {
  return static_cast<const Bytes*>(sample)->size();
}

bool SerializeInto(const ddsi_sertype*, const void* sample, void* dst, size_t dst_size) {
  const Bytes& b = *static_cast<const Bytes*>(sample);
  if (b.size() > dst_size) return false;
  std::memcpy(dst, b.data(), b.size());
  return true;
}

const ddsi_sertype_ops kTypeOps = [] {
  ddsi_sertype_ops ops{};
  ops.version = ddsi_sertype_v0;
  ops.free = FreeType;
  ops.zero_samples = ZeroSamples;
  ops.realloc_samples = ReallocSamples;
  ops.free_samples = FreeSamples;
  ops.equal = EqualTypes;
  ops.hash = HashType;
  ops.get_serialized_size = SerializedSize;
  ops.serialize_into = SerializeInto;
  return ops;  // no type_id / type_map / type_info: matched by name (no XTypes)
}();

}  // namespace

ddsi_sertype* NewRawCdrType(const std::string& dds_type_name) {
  auto* t = new ddsi_sertype();
  ddsi_sertype_init(t, dds_type_name.c_str(), &kTypeOps, &kSampleOps, /*topickind_no_key=*/true);
  return t;
}

ddsi_serdata* NewRawCdrSample(const ddsi_sertype* type, const std::vector<uint8_t>& bytes) {
  RawSample* s = NewSample(type, SDK_DATA);
  s->bytes = bytes;
  return &s->base;
}

const std::vector<uint8_t>& RawCdrBytes(const ddsi_serdata* sample) { return AsRaw(sample)->bytes; }

}  // namespace rvlio::live_detail
