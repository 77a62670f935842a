// qswarm-attacker: a stranger on a run's DDS domain, or a member with a stolen certificate, for
// the attack tests (tests/swarm/attack_test.cpp). Not a product binary. It learns the run id as a
// real attacker would, from the first sample heard on the wildcard partition qswarm-run-*
// (unless given --run-id), then, on the state and record streams:
//   relay        republishes agent VICTIM's real samples with a sequence number --seq-offset
//                higher and its consensus state and every flow it owns shifted by --offset (the
//                forged-flow relay); --copies N sends each N times, outpacing the real agent;
//   impersonate  publishes as agent --as (default VICTIM) at --rate Hz: its real samples shifted
//                by --offset when heard, a state at --offset otherwise, with a newer start time;
// for --for wall seconds from its first publication (default: until SIGTERM), then it stops.
// With --keystore and --identity it joins as that identity of a DDS-Security keystore, and its
// writers are bound to that identity's agent (the only partitions its permissions allow).
// It prints what it did; --report FILE gets key=value lines. Exit 0 when done or stopped by a
// signal, 3 when it heard no run within --learn-timeout, 2 for bad flags.
#include <CLI/CLI.hpp>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "common/clock/clock.hpp"
#include "common/dds/dds_bus.hpp"
#include "common/dds/idl_convert.hpp"
#include "common/dds/qos.hpp"
#include "common/transport/name_list.hpp"
#include "common/transport/port_plan.hpp"

#include "swarm_statePubSubTypes.h"

namespace {

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }

struct Flags {
  int domain = -1;
  std::string mode = "relay";
  unsigned victim = 1;
  unsigned as = 0;  // 0: the victim
  std::string run_id;
  std::string keystore, identity;
  std::uint64_t seq_offset = 1'000'000;
  std::vector<double> offset = {50.0, 0.0, 0.0};
  int copies = 1;
  double rate_hz = 200.0;
  double for_s = -1.0;
  double learn_timeout_s = 30.0;
  std::string report;
  std::string streams = "both";
  std::string unicast_peers;  // FIRST:COUNT: a secure run discovers by unicast within its block
  std::string interface = "127.0.0.1";  // where its participant binds
  std::string peer_hosts;  // A,B,...: the hosts whose --unicast-peers ids it announces to
};

using qswarm::AgentId;
using qswarm::StateMessage;
using qswarm::Vec3;
namespace dds = eprosima::fastdds::dds;

// What the attacker hears: every run's state stream (the wildcard partition), the newest sample
// of each agent by arrival, leaving out its own forger's (a plain reader of its own: the product's
// gate would take the forger's samples as the agent's).
class Ear : public dds::DataReaderListener {
 public:
  explicit Ear(const qswarm::ParticipantOptions& part) : participant_(part) {
    dds::DomainParticipant* p = participant_.get();
    type_.register_type(p);
    topic_ = p->create_topic("qswarm/agent_state", type_.get_type_name(), dds::TOPIC_QOS_DEFAULT);
    dds::SubscriberQos sq = dds::SUBSCRIBER_QOS_DEFAULT;
    sq.partition().push_back("qswarm-run-*");
    subscriber_ = p->create_subscriber(sq);
    dds::DataReaderQos rq = qswarm::best_effort_reader_qos();
    rq.resource_limits().max_instances = 128;
    rq.resource_limits().max_samples = 128;
    rq.resource_limits().max_samples_per_instance = 1;
    reader_ = topic_ && subscriber_ ? subscriber_->create_datareader(topic_, rq, this) : nullptr;
    if (!reader_) throw std::runtime_error("qswarm-attacker: cannot create its reader");
  }
  ~Ear() override {
    reader_->set_listener(nullptr);
    subscriber_->delete_datareader(reader_);
  }
  Ear(const Ear&) = delete;
  Ear& operator=(const Ear&) = delete;

  // Samples whose writer has this GUID prefix are the attacker's own.
  void ignore(const std::array<std::uint8_t, 12>& prefix) {
    std::lock_guard<std::mutex> lock(mu_);
    own_ = prefix;
  }
  std::optional<std::uint64_t> run_id() const {
    std::lock_guard<std::mutex> lock(mu_);
    return run_id_;
  }
  std::string learned() const {
    std::lock_guard<std::mutex> lock(mu_);
    return learned_;
  }
  std::uint64_t heard() const {
    std::lock_guard<std::mutex> lock(mu_);
    return heard_;
  }
  std::optional<StateMessage> latest(AgentId id, std::uint64_t run) const {
    std::lock_guard<std::mutex> lock(mu_);
    const auto it = latest_.find(id);
    if (it == latest_.end() || it->second.run_id != run) return std::nullopt;
    return it->second;
  }
  // The newest stamp any agent of the run sent (the run's clock, as far as it is heard).
  double stamp(std::uint64_t run) const {
    std::lock_guard<std::mutex> lock(mu_);
    double t = 0.0;
    for (const auto& [id, m] : latest_)
      if (m.run_id == run) t = std::max(t, m.stamp_s);
    return t;
  }

  void on_data_available(dds::DataReader* r) override {
    qswarm_msgs::AgentState s;
    dds::SampleInfo info;
    while (r->take_next_sample(&s, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      std::lock_guard<std::mutex> lock(mu_);
      if (own_ && std::memcmp(info.publication_handle.value, own_->data(), 12) == 0) continue;
      const StateMessage m = qswarm::from_idl(s);
      ++heard_;
      latest_[m.view.id] = m;
      if (!run_id_ && m.run_id != 0) {
        run_id_ = m.run_id;
        learned_ = "wildcard, from agent " + std::to_string(m.view.id);
      }
    }
  }

 private:
  qswarm::DdsParticipant participant_;
  dds::TypeSupport type_{new qswarm_msgs::AgentStatePubSubType()};
  dds::Topic* topic_ = nullptr;
  dds::Subscriber* subscriber_ = nullptr;
  dds::DataReader* reader_ = nullptr;
  mutable std::mutex mu_;
  std::optional<std::array<std::uint8_t, 12>> own_;
  std::optional<std::uint64_t> run_id_;
  std::string learned_ = "none";
  std::uint64_t heard_ = 0;
  std::map<AgentId, StateMessage> latest_;
};

std::int64_t now_ns() { return qswarm::system_clock().wall_ns(); }

void sleep_s(double s) {
  std::this_thread::sleep_for(std::chrono::microseconds(static_cast<long>(s * 1e6)));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"qswarm-attacker: forges samples on a run's DDS domain (tests only)"};
  Flags f;
  app.add_option("--domain", f.domain, "the DDS domain")
      ->required()
      ->check(CLI::Range(0, static_cast<int>(qswarm::PortPlan::kMaxDomain)));
  app.add_option("--mode", f.mode, "relay or impersonate")
      ->check(CLI::IsMember({"relay", "impersonate"}));
  app.add_option("--victim", f.victim, "the agent relayed or impersonated")
      ->check(CLI::Range(1, 10000));
  app.add_option("--as", f.as, "the id to publish as (default: the victim)")
      ->check(CLI::Range(1, 10000));
  app.add_option("--run-id", f.run_id, "the run id in hex (default: learned from the wildcard)");
  app.add_option("--keystore", f.keystore, "a swarm keys keystore to join with");
  app.add_option("--identity", f.identity, "its identity to use (agent-ID)");
  app.add_option("--seq-offset", f.seq_offset, "added to relayed sequence numbers");
  app.add_option("--offset", f.offset, "X Y Z [m] added to states and owned flows")->expected(3);
  app.add_option("--copies", f.copies, "relay: sends per real sample")->check(CLI::Range(1, 100));
  app.add_option("--rate", f.rate_hz, "impersonate: samples per second")
      ->check(CLI::Range(1.0, 2000.0));
  app.add_option("--for", f.for_s, "wall seconds to attack from the first sample sent");
  app.add_option("--learn-timeout", f.learn_timeout_s, "wall seconds to hear a run");
  app.add_option("--report", f.report, "write key=value lines here");
  app.add_option("--unicast-peers", f.unicast_peers,
                 "FIRST:COUNT: announce to these participant ids of the port plan, as a secure "
                 "run's own processes do (they hear no multicast)");
  app.add_option("--interface", f.interface, "IPv4 address its participant binds to");
  app.add_option("--peer-hosts", f.peer_hosts,
                 "A,B,...: IPv4 addresses of the hosts whose --unicast-peers ids it announces to "
                 "(default: its own interface)");
  app.add_option("--streams", f.streams, "state, record or both")
      ->check(CLI::IsMember({"state", "record", "both"}));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  if (f.keystore.empty() != f.identity.empty()) {
    std::fprintf(stderr, "qswarm-attacker: --keystore and --identity go together\n");
    return 2;
  }
  const AgentId as = f.as != 0 ? f.as : f.victim;
  const Vec3 off(f.offset[0], f.offset[1], f.offset[2]);
  std::signal(SIGTERM, on_signal);
  std::signal(SIGINT, on_signal);

  qswarm::ParticipantOptions part;
  part.domain_id = static_cast<std::uint32_t>(f.domain);
  part.keystore = f.keystore;
  part.identity = f.identity;
  part.name = "qswarm-attacker-ear";
  part.interface = f.interface;
  part.unicast_peer_hosts = qswarm::split_names(f.peer_hosts);
  if (!f.unicast_peers.empty()) {
    std::string why;
    const auto peers = qswarm::parse_unicast_peers(f.unicast_peers, why);
    if (!peers) {
      std::fprintf(stderr, "qswarm-attacker: --unicast-peers: %s\n", why.c_str());
      return 2;
    }
    part.unicast_peers_first = peers->first;
    part.unicast_peers_count = peers->second;
  }
  Ear ear(part);
  std::optional<std::uint64_t> given;
  if (!f.run_id.empty()) given = std::stoull(f.run_id, nullptr, 16);
  const double start = qswarm::system_clock().now_s();
  while (!g_stop && !given && !ear.run_id() &&
         qswarm::system_clock().now_s() - start < f.learn_timeout_s)
    sleep_s(0.01);
  const std::optional<std::uint64_t> known = given ? given : ear.run_id();
  const auto report = [&](std::uint64_t published, std::int64_t first_ns, std::int64_t last_ns) {
    char id[24] = "none";
    if (known) std::snprintf(id, sizeof id, "%016llx", static_cast<unsigned long long>(*known));
    const std::string learned = given ? "given" : ear.learned();
    std::printf("qswarm-attacker: run %s (%s), heard %llu samples, published %llu\n", id,
                learned.c_str(), static_cast<unsigned long long>(ear.heard()),
                static_cast<unsigned long long>(published));
    std::fflush(stdout);
    if (f.report.empty()) return;
    std::ofstream out(f.report);
    out << "run_id=" << id << "\nlearned=" << learned << "\nheard=" << ear.heard()
        << "\npublished=" << published << "\nfirst_ns=" << first_ns << "\nlast_ns=" << last_ns
        << "\n";
  };
  if (!known) {
    report(0, 0, 0);
    return g_stop ? 0 : 3;
  }
  const std::uint64_t run = *known;
  // The forger's writers: into the run's partition and the partition of the agent it is bound to
  // (a member's certificate allows only its own; a stranger names the agent it forges).
  qswarm::DdsOptions forge_opts;
  forge_opts.participant = part;
  forge_opts.participant.name = "qswarm-attacker";
  forge_opts.state.max_agents = 64;
  forge_opts.state.run_id = run;
  forge_opts.state.self = as;
  if (f.identity.rfind("agent-", 0) == 0)
    forge_opts.state.self = static_cast<AgentId>(std::stoul(f.identity.substr(6)));
  qswarm::DdsBus forger(forge_opts);
  {
    std::array<std::uint8_t, 12> prefix{};
    std::memcpy(prefix.data(), forger.participant().get()->guid().guidPrefix.value, 12);
    ear.ignore(prefix);
  }

  const std::int64_t life = now_ns();  // "newer" than every agent of the run
  std::uint64_t published = 0, seq = 0, last_relayed = 0;
  std::int64_t first_ns = 0, last_ns = 0;
  // Impersonation starts from the agent's real sample heard last before it (it stops hearing the
  // agent's own once the agents take the forger's).
  std::optional<StateMessage> base;
  const auto send = [&](StateMessage m) {
    m.wall_ns = now_ns();
    if (f.streams != "record") forger.publish(m);
    if (f.streams != "state") forger.record(m);
    ++published;
    if (first_ns == 0) first_ns = m.wall_ns;
    last_ns = m.wall_ns;
  };
  const auto shift = [&](StateMessage& m) {
    m.view.q += off;
    for (auto& flow : m.view.flows) flow.flow += off;
  };
  // An impersonator waits a little to hear the agent it copies (a stranger to a secure run never
  // does, and forges from nothing).
  const double heard_by = qswarm::system_clock().now_s() + 5.0;
  while (f.mode == "impersonate" && !g_stop && !ear.latest(as, run) &&
         qswarm::system_clock().now_s() < heard_by)
    sleep_s(0.01);
  const double period = f.mode == "relay" ? 0.002 : 1.0 / f.rate_hz;
  double next = qswarm::system_clock().now_s();
  while (!g_stop) {
    if (f.for_s >= 0.0 && first_ns != 0 &&
        static_cast<double>(now_ns() - first_ns) * 1e-9 >= f.for_s)
      break;
    if (f.mode == "relay") {
      const std::optional<StateMessage> real = ear.latest(f.victim, run);
      if (real && real->seq != last_relayed) {
        last_relayed = real->seq;
        for (int k = 0; k < f.copies; ++k) {
          StateMessage m = *real;
          m.view.id = as;
          m.seq = f.seq_offset + real->seq * static_cast<std::uint64_t>(f.copies) +
                  static_cast<std::uint64_t>(k);
          shift(m);
          send(m);
        }
      }
    } else {
      if (first_ns == 0) base = ear.latest(as, run);
      StateMessage m;
      if (base) {
        m = *base;
        shift(m);
      } else {
        m.view.q = m.view.q0 = m.p_W = off;
      }
      m.stamp_s = std::max(m.stamp_s, ear.stamp(run));
      m.view.id = as;
      m.run_id = run;
      m.incarnation = life;
      m.seq = ++seq;
      m.phase = qswarm::Phase::kRunning;
      send(m);
    }
    next += period;
    const double now = qswarm::system_clock().now_s();
    if (next > now) sleep_s(next - now);
    if (next < now - 1.0) next = now;
  }
  report(published, first_ns, last_ns);
  return 0;
}
