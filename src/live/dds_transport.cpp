// The ROS 2 transport: ROS 2's conventions on Eclipse Cyclone DDS directly
// (docs/live.md "ROS 2 on DDS"), without a ROS 2 installation:
//   - topic "/a/b" is the DDS topic "rt/a/b";
//   - type "pkg/msg/T" is the DDS type "pkg::msg::dds_::T_", its samples CDR
//     (XCDR1, little endian) with the encapsulation header, encoded and
//     decoded by formats/cdr.h through the raw CDR type (raw_cdr_type.h);
//   - the participant's USER_DATA is "enclave=/;", as rmw_cyclonedds_cpp sets it;
//   - subscriptions are best effort, keep last (the sensor-data QoS of
//     drivers; a best-effort reader matches best-effort and reliable
//     writers); publications reliable, keep last 10, volatile (ROS 2's
//     default QoS, which reliable and best-effort readers both match).
// A subscription waits until a writer of its topic is discovered and takes
// that writer's type, so a topic of the wrong type is reported by the
// decoder (LiveSensorSource) instead of never matching.
#include "dds_transport.h"

#include <cstdlib>

#include <dds/ddsi/ddsi_serdata.h>

#include "raw_cdr_type.h"
#include "rvlio/formats/cdr.h"

namespace rvlio::live_detail {
namespace {

constexpr int kWriterDepth = 10;  // ROS 2's default QoS
constexpr int kSensorDepth = 5;   // ROS 2's sensor-data QoS
constexpr dds_duration_t kPollNs = DDS_MSECS(50);

class DdsQos {
 public:
  DdsQos() : qos_(dds_create_qos()) {}
  ~DdsQos() { dds_delete_qos(qos_); }
  DdsQos(const DdsQos&) = delete;
  DdsQos& operator=(const DdsQos&) = delete;
  dds_qos_t* get() const { return qos_; }

 private:
  dds_qos_t* qos_;
};

void SetCdrOnly(dds_qos_t* qos) {
  dds_data_representation_id_t xcdr1 = DDS_DATA_REPRESENTATION_XCDR1;
  dds_qset_data_representation(qos, 1, &xcdr1);
}

Status DdsError(const std::string& what, dds_return_t rc) {
  return Status::InvalidInput(what + ": " + dds_strretcode(rc));
}

}  // namespace

// "sensor_msgs/msg/Imu" -> "sensor_msgs::msg::dds_::Imu_" and back.
std::string DdsTypeName(const std::string& ros_type) {
  const size_t slash = ros_type.rfind('/');
  std::string pkg = ros_type.substr(0, slash), name = ros_type.substr(slash + 1);
  std::string out;
  for (char c : pkg) out += c == '/' ? std::string("::") : std::string(1, c);
  return out + "::dds_::" + name + "_";
}

std::string RosTypeName(const std::string& dds_type) {
  std::string t = dds_type;
  const size_t dds = t.find("::dds_::");
  if (dds != std::string::npos) t.erase(dds, 6);  // "::dds_::" -> "::"
  if (!t.empty() && t.back() == '_') t.pop_back();
  std::string out;
  for (size_t i = 0; i < t.size(); ++i) {
    if (t.compare(i, 2, "::") == 0) {
      out += '/';
      ++i;
    } else {
      out += t[i];
    }
  }
  return out;
}

std::string DdsTopicName(const std::string& ros_topic) {
  return "rt" + (ros_topic.empty() || ros_topic[0] != '/' ? "/" + ros_topic : ros_topic);
}

DdsTransport::~DdsTransport() {
  Shutdown();
  if (participant_ > 0) dds_delete(participant_);
}

Status DdsTransport::Init(int domain_id) {
  domain_id_ = domain_id;
  DdsQos qos;
  const std::string enclave = "enclave=/;";
  dds_qset_userdata(qos.get(), enclave.data(), enclave.size());
  participant_ = dds_create_participant(static_cast<dds_domainid_t>(domain_id), qos.get(), nullptr);
  if (participant_ < 0)
    return DdsError("DDS participant in domain " + std::to_string(domain_id), participant_);
  publications_ =
      dds_create_reader(participant_, DDS_BUILTIN_TOPIC_DCPSPUBLICATION, nullptr, nullptr);
  if (publications_ < 0) return DdsError("DDS publication discovery", publications_);
  return Status::Ok();
}

std::string DdsTransport::origin() const {
  return "ROS 2 on DDS, domain " + std::to_string(domain_id_);
}

Status DdsTransport::Subscribe(const std::string& topic, int depth, MessageCallback callback) {
  threads_.emplace_back([this, topic, depth, cb = std::move(callback)] { Receive(topic, depth, cb); });
  return Status::Ok();
}

Status DdsTransport::Advertise(const OutputTopics& t) {
  const std::pair<const std::string*, const char*> writers[] = {
      {&t.odometry, cdr::kOdometryType}, {&t.odometry_imu, cdr::kOdometryType},
      {&t.cloud, cdr::kPointCloud2Type}, {&t.path, cdr::kPathType},
      {&t.map, cdr::kPointCloud2Type},   {&t.status, cdr::kDiagnosticArrayType},
      {&t.tf, cdr::kTfMessageType}};
  for (const auto& [topic, type] : writers)
    if (Status s = AdvertiseRaw(*topic, type, true); !s.ok()) return s;
  topics_ = std::make_unique<OutputTopics>(t);
  return Status::Ok();
}

void DdsTransport::Publish(OdometryTopic which, const OdometryMessage& msg) {
  PublishRaw(which == OdometryTopic::kScanRate ? topics_->odometry : topics_->odometry_imu,
             cdr::EncodeOdometry(msg));
}
void DdsTransport::PublishTf(const TransformMessage& msg) {
  PublishRaw(topics_->tf, cdr::EncodeTfMessage({msg}));
}
void DdsTransport::Publish(CloudTopic which, const PointCloud2View& cloud,
                           const std::string& frame_id) {
  PublishRaw(which == CloudTopic::kMap ? topics_->map : topics_->cloud,
             cdr::EncodePointCloud2(cloud, frame_id, true));
}
void DdsTransport::Publish(const PathMessage& msg) { PublishRaw(topics_->path, cdr::EncodePath(msg)); }
void DdsTransport::Publish(const DiagnosticMessage& msg) {
  PublishRaw(topics_->status, cdr::EncodeDiagnosticArray(msg));
}

void DdsTransport::Shutdown() {
  stop_ = true;
  for (std::thread& t : threads_)
    if (t.joinable()) t.join();
  threads_.clear();
}

// Reliable writers wait until their readers acknowledged everything.
void DdsTransport::Flush() {
  for (const auto& [topic, writer] : writers_) (void)dds_wait_for_acks(writer.entity, DDS_MSECS(500));
}

Status DdsTransport::AdvertiseRaw(const std::string& topic, const std::string& ros_type,
                                  bool reliable) {
  // dds_create_topic_sertype may replace `type` by an equal one already registered.
  ddsi_sertype* type = NewRawCdrType(DdsTypeName(ros_type));
  const dds_entity_t t = dds_create_topic_sertype(participant_, DdsTopicName(topic).c_str(), &type,
                                                  nullptr, nullptr, nullptr);
  if (t < 0) return DdsError("DDS topic " + DdsTopicName(topic), t);
  DdsQos qos;
  if (reliable) {
    dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
    dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, kWriterDepth);
  } else {
    dds_qset_reliability(qos.get(), DDS_RELIABILITY_BEST_EFFORT, 0);
    dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, kSensorDepth);
  }
  dds_qset_durability(qos.get(), DDS_DURABILITY_VOLATILE);
  SetCdrOnly(qos.get());
  const dds_entity_t w = dds_create_writer(participant_, t, qos.get(), nullptr);
  if (w < 0) return DdsError("DDS writer on " + DdsTopicName(topic), w);
  writers_[topic] = Writer{w, type};
  return Status::Ok();
}

void DdsTransport::PublishRaw(const std::string& topic, const std::vector<uint8_t>& bytes) {
  const auto it = writers_.find(topic);
  if (it == writers_.end()) return;
  (void)dds_writecdr(it->second.entity, NewRawCdrSample(it->second.type, bytes));
}

int DdsTransport::MatchedReaders(const std::string& topic) const {
  const auto it = writers_.find(topic);
  dds_publication_matched_status_t status{};
  if (it == writers_.end() || dds_get_publication_matched_status(it->second.entity, &status) < 0)
    return 0;
  return static_cast<int>(status.current_count);
}

std::optional<DdsTransport::Offered> DdsTransport::DiscoveredWriter(const std::string& topic) {
  const std::string name = DdsTopicName(topic);
  std::lock_guard<std::mutex> lock(discovery_mutex_);
  constexpr int kBatch = 16;
  void* samples[kBatch] = {};
  dds_sample_info_t infos[kBatch];
  for (;;) {
    const dds_return_t n = dds_take(publications_, samples, infos, kBatch, kBatch);
    if (n <= 0) break;
    for (dds_return_t i = 0; i < n; ++i) {
      const auto* e = static_cast<const dds_builtintopic_endpoint_t*>(samples[i]);
      if (!infos[i].valid_data || e->topic_name == nullptr || e->type_name == nullptr) continue;
      dds_reliability_kind_t kind = DDS_RELIABILITY_BEST_EFFORT;
      dds_duration_t blocking = 0;
      const bool reliable = e->qos != nullptr && dds_qget_reliability(e->qos, &kind, &blocking) &&
                            kind == DDS_RELIABILITY_RELIABLE;
      discovered_.emplace(e->topic_name, Offered{e->type_name, reliable});
    }
    dds_return_loan(publications_, samples, n);
  }
  const auto it = discovered_.find(name);
  if (it == discovered_.end()) return std::nullopt;
  return it->second;
}

// One topic's thread: waits for a writer of the topic to be discovered,
// reads with its type and reliability, hands every sample to `callback`
// until Shutdown.
void DdsTransport::Receive(const std::string& topic, int depth, const MessageCallback& callback) {
  std::optional<Offered> offered;
  while (!stop_ && !(offered = DiscoveredWriter(topic))) dds_sleepfor(kPollNs);
  if (stop_) return;
  ddsi_sertype* type = NewRawCdrType(offered->dds_type);
  const dds_entity_t t = dds_create_topic_sertype(participant_, DdsTopicName(topic).c_str(), &type,
                                                  nullptr, nullptr, nullptr);
  DdsQos qos;
  if (offered->reliable)
    dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  else
    dds_qset_reliability(qos.get(), DDS_RELIABILITY_BEST_EFFORT, 0);
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, depth);
  SetCdrOnly(qos.get());
  const dds_entity_t reader = t < 0 ? t : dds_create_reader(participant_, t, qos.get(), nullptr);
  if (reader < 0) return;  // the wait for the topic's first message reports it
  const std::string ros_type = RosTypeName(offered->dds_type);
  const dds_entity_t waitset = dds_create_waitset(participant_);
  const dds_entity_t readable = dds_create_readcondition(reader, DDS_ANY_STATE);
  dds_waitset_attach(waitset, readable, reader);
  while (!stop_) {
    if (dds_waitset_wait(waitset, nullptr, 0, kPollNs) <= 0) continue;
    ddsi_serdata* sample = nullptr;
    dds_sample_info_t info;
    while (!stop_ && dds_takecdr(reader, &sample, 1, &info, DDS_ANY_STATE) == 1) {
      if (info.valid_data) {
        const std::vector<uint8_t>& bytes = RawCdrBytes(sample);
        callback(bytes.data(), bytes.size(), ros_type);
      }
      ddsi_serdata_unref(sample);
    }
  }
  dds_delete(waitset);
}

StatusOr<std::unique_ptr<Transport>> ConnectRos2(const LiveOptions& live) {
  int domain = live.ros2_domain_id;
  if (domain < 0) {
    const char* env = std::getenv("ROS_DOMAIN_ID");
    char* end = nullptr;
    const long v = env != nullptr && *env != '\0' ? std::strtol(env, &end, 10) : 0;
    if (env != nullptr && *env != '\0' && (*end != '\0' || v < 0 || v > 232))
      return Status::InvalidInput("ROS_DOMAIN_ID '" + std::string(env) +
                                  "' is not a domain id (0..232)");
    domain = static_cast<int>(v);
  }
  auto transport = std::make_unique<DdsTransport>();
  if (Status s = transport->Init(domain); !s.ok()) return s;
  return std::unique_ptr<Transport>(std::move(transport));
}

}  // namespace rvlio::live_detail
