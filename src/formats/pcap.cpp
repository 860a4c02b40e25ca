// Classic pcap files (formats/pcap.h): reading UDP datagrams with IPv4 fragment
// reassembly, and writing Ethernet/IPv4/UDP captures.
#include "rvlio/formats/pcap.h"

#include <sys/stat.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

namespace rvlio {
namespace {

constexpr uint32_t kMagicMicro = 0xA1B2C3D4u;
constexpr uint32_t kMagicNano = 0xA1B23C4Du;
constexpr uint32_t kLinkNull = 0, kLinkEthernet = 1, kLinkRaw = 101, kLinkSll = 113,
                   kLinkSll2 = 276, kLinkIpv4 = 228;
constexpr size_t kMaxRecordBytes = size_t{1} << 20;  // far above any UDP datagram
constexpr size_t kMaxPendingDatagrams = 256;          // IPv4 reassembly buffers held at once

uint32_t Le32(const uint8_t* p) {
  return uint32_t{p[0]} | uint32_t{p[1]} << 8 | uint32_t{p[2]} << 16 | uint32_t{p[3]} << 24;
}
uint16_t Be16(const uint8_t* p) { return static_cast<uint16_t>(p[0] << 8 | p[1]); }
uint32_t Be32(const uint8_t* p) { return uint32_t{Be16(p)} << 16 | Be16(p + 2); }

std::string Ipv4Text(uint32_t a) {
  char buf[16];
  std::snprintf(buf, sizeof(buf), "%u.%u.%u.%u", a >> 24, (a >> 16) & 255, (a >> 8) & 255, a & 255);
  return buf;
}

std::string Ipv6Text(const uint8_t* a) {
  std::string out;
  char buf[8];
  for (int i = 0; i < 16; i += 2) {
    std::snprintf(buf, sizeof(buf), "%s%x", i == 0 ? "" : ":", Be16(a + i));
    out += buf;
  }
  return out;
}

void PutLe16(std::string* s, uint16_t v) {
  s->push_back(static_cast<char>(v & 255));
  s->push_back(static_cast<char>(v >> 8));
}
void PutLe32(std::string* s, uint32_t v) {
  PutLe16(s, static_cast<uint16_t>(v & 0xFFFF));
  PutLe16(s, static_cast<uint16_t>(v >> 16));
}
void PutBe16(std::vector<uint8_t>* s, size_t at, uint16_t v) {
  (*s)[at] = static_cast<uint8_t>(v >> 8);
  (*s)[at + 1] = static_cast<uint8_t>(v & 255);
}

uint16_t Ipv4Checksum(const uint8_t* h, size_t n) {
  uint32_t sum = 0;
  for (size_t i = 0; i + 1 < n; i += 2) sum += Be16(h + i);
  while (sum >> 16) sum = (sum & 0xFFFF) + (sum >> 16);
  return static_cast<uint16_t>(~sum);
}

}  // namespace

bool IsPcapMagic(const uint8_t* head, size_t size) {
  if (size < 4) return false;
  const uint32_t m = Le32(head);
  auto swapped = [](uint32_t v) {
    return (v >> 24) | ((v >> 8) & 0xFF00u) | ((v << 8) & 0xFF0000u) | (v << 24);
  };
  return m == kMagicMicro || m == kMagicNano || m == swapped(kMagicMicro) || m == swapped(kMagicNano);
}

bool IsPcapngMagic(const uint8_t* head, size_t size) {
  return size >= 4 && Le32(head) == 0x0A0D0D0Au;
}

uint32_t PcapReader::Word32(const uint8_t* p) const { return swap_ ? Be32(p) : Le32(p); }
uint16_t PcapReader::Word16(const uint8_t* p) const {
  return swap_ ? Be16(p) : static_cast<uint16_t>(p[0] | p[1] << 8);
}

StatusOr<PcapReader> PcapReader::Open(const std::string& path) {
  PcapReader r;
  r.path_ = path;
  auto file = std::make_unique<std::ifstream>(path, std::ios::binary);
  if (!*file) return Status::InvalidInput("cannot read capture '" + path + "'");
  r.in_ = std::move(file);
  return Start(std::move(r));
}

StatusOr<PcapReader> PcapReader::OpenBuffer(std::string bytes, const std::string& name) {
  PcapReader r;
  r.path_ = name;
  r.in_ = std::make_unique<std::istringstream>(std::move(bytes), std::ios::binary);
  return Start(std::move(r));
}

StatusOr<PcapReader> PcapReader::Start(PcapReader r) {
  const std::string& path = r.path_;
  uint8_t h[24];
  r.in_->read(reinterpret_cast<char*>(h), sizeof(h));
  const size_t got = static_cast<size_t>(r.in_->gcount());
  if (IsPcapngMagic(h, got))
    return Status::InvalidInput("capture '" + path + "' is pcapng; rvlio reads classic pcap "
                                "(convert: editcap -F pcap IN OUT)");
  if (got < sizeof(h) || !IsPcapMagic(h, got))
    return Status::InvalidInput("'" + path + "' is not a pcap capture (too short or no pcap magic)");
  const uint32_t m = Le32(h);
  r.swap_ = m != kMagicMicro && m != kMagicNano;
  r.nano_ = m == kMagicNano || Be32(h) == kMagicNano;
  r.link_ = r.Word32(h + 20) & 0x0FFFFFFFu;  // the upper bits carry FCS flags
  if (r.link_ != kLinkEthernet && r.link_ != kLinkRaw && r.link_ != kLinkSll &&
      r.link_ != kLinkSll2 && r.link_ != kLinkNull && r.link_ != kLinkIpv4)
    return Status::InvalidInput("capture '" + path + "' has link type " + std::to_string(r.link_) +
                                "; rvlio reads Ethernet, Linux cooked, raw IP and loopback captures");
  return r;
}

StatusOr<bool> PcapReader::Record(std::vector<uint8_t>* data, TimeNs* t_ns) {
  uint8_t h[16];
  in_->read(reinterpret_cast<char*>(h), sizeof(h));
  const size_t got = static_cast<size_t>(in_->gcount());
  if (got == 0) return false;
  const std::string where = "capture '" + path_ + "' record " + std::to_string(index_ + 1);
  if (got < sizeof(h)) return Status::InvalidInput(where + ": the file ends inside its header (truncated)");
  const uint32_t sec = Word32(h), frac = Word32(h + 4), incl = Word32(h + 8), orig = Word32(h + 12);
  if (incl > kMaxRecordBytes)
    return Status::InvalidInput(where + " claims " + std::to_string(incl) + " bytes (corrupt)");
  data->resize(incl);
  in_->read(reinterpret_cast<char*>(data->data()), static_cast<std::streamsize>(incl));
  if (static_cast<uint32_t>(in_->gcount()) != incl)
    return Status::InvalidInput(where + ": the file ends inside its " + std::to_string(incl) +
                                " bytes (truncated)");
  if (orig > incl)
    return Status::InvalidInput(where + ": captured " + std::to_string(incl) + " of its " +
                                std::to_string(orig) + " bytes (snap length too small: truncated packet)");
  ++index_;
  *t_ns = static_cast<TimeNs>(sec) * 1000000000 + static_cast<TimeNs>(frac) * (nano_ ? 1 : 1000);
  return true;
}

StatusOr<bool> PcapReader::Next(UdpDatagram* out) {
  if (!error_.ok()) return error_;
  while (true) {
    TimeNs t_ns = 0;
    StatusOr<bool> got = Record(&record_, &t_ns);
    if (!got.ok()) return error_ = got.status();
    if (!*got) {
      stats_.incomplete_datagrams += static_cast<int64_t>(pending_.size());
      pending_.clear();
      return false;
    }
    ++stats_.records;
    if (Frame(record_, t_ns, out)) {
      ++stats_.udp_datagrams;
      return true;
    }
  }
}

// Link layer -> IP.
bool PcapReader::Frame(const std::vector<uint8_t>& f, TimeNs t_ns, UdpDatagram* out) {
  const uint8_t* p = f.data();
  size_t n = f.size();
  uint16_t ether = 0;  // 0: the version nibble decides
  if (link_ == kLinkEthernet) {
    if (n < 14) return ++stats_.other_records, false;
    ether = Be16(p + 12);
    p += 14, n -= 14;
    while ((ether == 0x8100 || ether == 0x88A8) && n >= 4) {  // 802.1Q / QinQ tags
      ether = Be16(p + 2);
      p += 4, n -= 4;
    }
  } else if (link_ == kLinkSll) {
    if (n < 16) return ++stats_.other_records, false;
    ether = Be16(p + 14);
    p += 16, n -= 16;
  } else if (link_ == kLinkSll2) {
    if (n < 20) return ++stats_.other_records, false;
    ether = Be16(p);
    p += 20, n -= 20;
  } else if (link_ == kLinkNull) {
    if (n < 4) return ++stats_.other_records, false;
    p += 4, n -= 4;
  }
  const int version = n > 0 ? p[0] >> 4 : 0;
  if ((ether == 0x0800 || ether == 0) && version == 4) {
    if (Ipv4(p, n, t_ns, out)) return true;
    return false;
  }
  if ((ether == 0x86DD || ether == 0) && version == 6) {
    if (Ipv6(p, n, t_ns, out)) return true;
    return false;
  }
  ++stats_.other_records;
  return false;
}

bool PcapReader::Ipv4(const uint8_t* p, size_t n, TimeNs t_ns, UdpDatagram* out) {
  if (n < 20) return ++stats_.other_records, false;
  const size_t ihl = static_cast<size_t>(p[0] & 15) * 4;
  const size_t total = Be16(p + 2);
  if (ihl < 20 || total < ihl || total > n || p[9] != 17) return ++stats_.other_records, false;
  const uint16_t flags = Be16(p + 6);
  const bool more = (flags & 0x2000) != 0;
  const size_t offset = static_cast<size_t>(flags & 0x1FFF) * 8;
  const uint32_t src = Be32(p + 12);
  out->src = Ipv4Text(src);
  if (!more && offset == 0) return Udp(p + ihl, total - ihl, t_ns, out);
  // A fragment: collect it; deliver the datagram once every byte is there.
  ++stats_.fragments;
  const FragmentKey key{src, Be32(p + 16), Be16(p + 4)};
  if (pending_.count(key) == 0 && pending_.size() >= kMaxPendingDatagrams) {
    ++stats_.incomplete_datagrams;  // the oldest buffer is given up
    pending_.erase(pending_.begin());
  }
  Pending& d = pending_[key];
  const size_t len = total - ihl;
  if (offset + len > 65535) return pending_.erase(key), ++stats_.incomplete_datagrams, false;
  if (d.bytes.size() < offset + len) {
    d.bytes.resize(offset + len);
    d.have.resize(offset + len, false);
  }
  std::copy(p + ihl, p + ihl + len, d.bytes.begin() + static_cast<std::ptrdiff_t>(offset));
  std::fill(d.have.begin() + static_cast<std::ptrdiff_t>(offset),
            d.have.begin() + static_cast<std::ptrdiff_t>(offset + len), true);
  if (!more) d.total = static_cast<int64_t>(offset + len);
  if (d.total < 0 || static_cast<int64_t>(d.bytes.size()) != d.total ||
      std::find(d.have.begin(), d.have.end(), false) != d.have.end())
    return false;
  const std::vector<uint8_t> whole = std::move(d.bytes);
  pending_.erase(key);
  return Udp(whole.data(), whole.size(), t_ns, out);
}

bool PcapReader::Ipv6(const uint8_t* p, size_t n, TimeNs t_ns, UdpDatagram* out) {
  if (n < 40 || p[6] != 17) return ++stats_.other_records, false;  // UDP right after the header
  const size_t len = Be16(p + 4);
  if (len > n - 40) return ++stats_.other_records, false;
  out->src = Ipv6Text(p + 8);
  return Udp(p + 40, len, t_ns, out);
}

bool PcapReader::Udp(const uint8_t* p, size_t n, TimeNs t_ns, UdpDatagram* out) {
  if (n < 8) return ++stats_.other_records, false;
  const size_t len = Be16(p + 4);
  if (len < 8 || len > n) return ++stats_.other_records, false;
  out->t_ns = t_ns;
  out->src_port = Be16(p);
  out->dst_port = Be16(p + 2);
  out->payload.assign(p + 8, p + len);
  return true;
}

// ---------------------------------------------------------------------------

Status PcapWriter::Open(const std::string& path, int mtu) {
  mtu_ = std::max(mtu, 68);
  if (Status s = file_.Open(path); !s.ok()) return s;
  std::string h;
  PutLe32(&h, kMagicNano);
  PutLe16(&h, 2);
  PutLe16(&h, 4);
  PutLe32(&h, 0);       // thiszone
  PutLe32(&h, 0);       // sigfigs
  PutLe32(&h, 262144);  // snaplen
  PutLe32(&h, kLinkEthernet);
  return file_.Append(h);
}

Status PcapWriter::Frame(TimeNs t_ns, const std::vector<uint8_t>& ip) {
  static constexpr uint8_t kEthernet[14] = {0xff, 0xff, 0xff, 0xff, 0xff, 0xff,  // broadcast
                                            0xbc, 0x0f, 0xa7, 0x00, 0x00, 0x01,  // sensor MAC
                                            0x08, 0x00};
  std::string rec;
  const uint32_t len = static_cast<uint32_t>(ip.size() + sizeof(kEthernet));
  PutLe32(&rec, static_cast<uint32_t>(t_ns / 1000000000));
  PutLe32(&rec, static_cast<uint32_t>(t_ns % 1000000000));
  PutLe32(&rec, len);
  PutLe32(&rec, len);
  rec.append(reinterpret_cast<const char*>(kEthernet), sizeof(kEthernet));
  rec.append(reinterpret_cast<const char*>(ip.data()), ip.size());
  return file_.Append(rec);
}

Status PcapWriter::Write(const UdpDatagram& d) {
  RVLIO_CHECK(d.t_ns >= 0);
  std::vector<uint8_t> udp(8 + d.payload.size());
  PutBe16(&udp, 0, d.src_port);
  PutBe16(&udp, 2, d.dst_port);
  PutBe16(&udp, 4, static_cast<uint16_t>(udp.size()));  // checksum 0: none (IPv4)
  std::copy(d.payload.begin(), d.payload.end(), udp.begin() + 8);
  const size_t chunk = static_cast<size_t>((mtu_ - 20) / 8 * 8);
  const uint16_t id = ip_id_++;
  for (size_t offset = 0; offset < udp.size(); offset += chunk) {
    const size_t len = std::min(chunk, udp.size() - offset);
    std::vector<uint8_t> ip(20 + len, 0);
    ip[0] = 0x45;
    PutBe16(&ip, 2, static_cast<uint16_t>(ip.size()));
    PutBe16(&ip, 4, id);
    const bool more = offset + len < udp.size();
    PutBe16(&ip, 6, static_cast<uint16_t>((more ? 0x2000 : 0) | (offset / 8)));
    ip[8] = 64;
    ip[9] = 17;
    const uint8_t src[4] = {169, 254, 10, 1}, dst[4] = {169, 254, 10, 2};
    std::copy(src, src + 4, ip.begin() + 12);
    std::copy(dst, dst + 4, ip.begin() + 16);
    PutBe16(&ip, 10, Ipv4Checksum(ip.data(), 20));
    std::copy(udp.begin() + static_cast<std::ptrdiff_t>(offset),
              udp.begin() + static_cast<std::ptrdiff_t>(offset + len), ip.begin() + 20);
    if (Status s = Frame(d.t_ns, ip); !s.ok()) return s;
  }
  return Status::Ok();
}

Status PcapWriter::Close() { return file_.Commit(); }

}  // namespace rvlio
