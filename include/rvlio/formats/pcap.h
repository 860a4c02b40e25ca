#pragma once
// Classic libpcap capture files (not pcapng): UDP datagrams out of Ethernet
// (with 802.1Q tags), Linux cooked (SLL, SLL2), raw IP or BSD loopback
// frames, IPv4 (fragments reassembled) or IPv6. Written from the file
// format's public description (a 24-byte file header whose magic gives the
// byte order and micro- or nanosecond stamps, then records of a 16-byte
// header and the captured bytes); no libpcap.
#include <cstdint>
#include <fstream>
#include <istream>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "rvlio/common/status.h"
#include "rvlio/common/time.h"
#include "rvlio/formats/atomic_file.h"

namespace rvlio {

struct UdpDatagram {
  TimeNs t_ns = 0;        // capture time of the (last fragment of the) datagram
  std::string src;        // source address, "192.168.1.10" or an IPv6 text
  uint16_t src_port = 0, dst_port = 0;
  std::vector<uint8_t> payload;
};

struct PcapStats {
  int64_t records = 0;
  int64_t udp_datagrams = 0;
  int64_t fragments = 0;          // IPv4 fragments seen
  int64_t other_records = 0;      // not UDP (ARP, TCP, ...): skipped
  int64_t incomplete_datagrams = 0;  // fragments never completed (at the end)
};

// True when the first bytes are a classic pcap magic (either byte order,
// micro- or nanosecond).
bool IsPcapMagic(const uint8_t* head, size_t size);
// True for a pcapng section header block.
bool IsPcapngMagic(const uint8_t* head, size_t size);

class PcapReader {
 public:
  // InvalidInput naming the path: missing, pcapng, not a pcap, unknown link type.
  static StatusOr<PcapReader> Open(const std::string& path);
  // The same on bytes in memory (`name` stands for the path in messages).
  static StatusOr<PcapReader> OpenBuffer(std::string bytes, const std::string& name);
  // The next UDP datagram; false at the end. A record cut short (the file
  // ends inside it) or cut by the snap length is InvalidInput naming the
  // record; every later call returns the same error.
  StatusOr<bool> Next(UdpDatagram* out);
  const PcapStats& stats() const { return stats_; }
  const std::string& path() const { return path_; }
  bool nanosecond() const { return nano_; }
  uint32_t link_type() const { return link_; }

  PcapReader(PcapReader&&) = default;
  PcapReader& operator=(PcapReader&&) = default;

 private:
  PcapReader() = default;
  static StatusOr<PcapReader> Start(PcapReader r);
  struct Pending {
    std::vector<uint8_t> bytes;
    std::vector<bool> have;
    int64_t total = -1;  // payload length once the last fragment arrived
  };
  using FragmentKey = std::tuple<uint32_t, uint32_t, uint16_t>;  // src, dst, id
  uint32_t Word32(const uint8_t* p) const;
  uint16_t Word16(const uint8_t* p) const;
  StatusOr<bool> Record(std::vector<uint8_t>* data, TimeNs* t_ns);
  bool Frame(const std::vector<uint8_t>& frame, TimeNs t_ns, UdpDatagram* out);
  bool Ipv4(const uint8_t* p, size_t n, TimeNs t_ns, UdpDatagram* out);
  bool Ipv6(const uint8_t* p, size_t n, TimeNs t_ns, UdpDatagram* out);
  bool Udp(const uint8_t* p, size_t n, TimeNs t_ns, UdpDatagram* out);

  std::string path_;
  std::unique_ptr<std::istream> in_;
  bool swap_ = false, nano_ = false;
  uint32_t link_ = 0;
  PcapStats stats_;
  std::map<FragmentKey, Pending> pending_;
  std::vector<uint8_t> record_;
  int64_t index_ = 0;
  Status error_;
};

// Writes a little-endian, nanosecond pcap of Ethernet/IPv4/UDP frames; a
// datagram larger than `mtu` bytes of IP is split into IPv4 fragments (as a
// capture on a 1500-byte MTU link records Ouster's large packets).
class PcapWriter {
 public:
  // Written atomically (formats/atomic_file.h): the file appears at Close().
  Status Open(const std::string& path, int mtu = 1500);
  Status Write(const UdpDatagram& datagram);
  Status Close();

 private:
  Status Frame(TimeNs t_ns, const std::vector<uint8_t>& ip);
  AtomicFileWriter file_;
  int mtu_ = 1500;
  uint16_t ip_id_ = 0;
};

}  // namespace rvlio
