// The live view in one process: the JSON it writes, Foxglove's protocol, the feed's bounds, the
// model's frames, the replay's clock, and the server against real sockets (a well-behaved client
// beside hostile ones). The feed is driven by the test: records made here, pushed when the test
// says, so nothing depends on a swarm's timing.
#include <google/protobuf/descriptor.pb.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <functional>
#include <future>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <thread>

#include "common/record/json_writer.hpp"
#include "common/record/record_sinks.hpp"
#include "common/record/run_dir.hpp"
#include "common/transport/utf8.hpp"
#include "common/view/foxglove_protocol.hpp"
#include "common/view/replay.hpp"
#include "common/view/view_channels.hpp"
#include "common/view/view_feed.hpp"
#include "common/view/view_model.hpp"
#include "common/view/view_server.hpp"

namespace qswarm {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;

records::Record sample_record(std::uint32_t id, double t, double x = 0.0) {
  records::Record r;
  records::AgentSample* s = r.mutable_sample();
  s->set_id(id);
  s->set_seq(static_cast<std::uint64_t>(t * 10));
  s->set_stamp_s(t);
  for (double v : {x + id, 2.0, 10.0}) s->add_position(v);
  for (double v : {x + id, 2.0, 10.0}) s->add_consensus(v);
  for (double v : {1.0, 0.0, 0.0, 0.0}) s->add_orientation(v);
  return r;
}

records::Record graph_record(double t, int agents, double lambda2) {
  records::Record r;
  records::GraphSnapshot* g = r.mutable_graph();
  g->set_t_s(t);
  g->set_agents(static_cast<std::uint32_t>(agents));
  g->set_lambda2(lambda2);
  g->set_disagreement_m(1.0 / (1.0 + t));
  for (int i = 1; i < agents; ++i) {
    records::GraphEdge* e = g->add_edges();
    e->set_a(static_cast<std::uint32_t>(i));
    e->set_b(static_cast<std::uint32_t>(i + 1));
    e->set_weight(0.5 * i);
  }
  return r;
}

records::Record event_record(double t, const std::string& kind, std::uint32_t agent,
                             const std::string& detail = "") {
  records::Record r;
  records::Event* e = r.mutable_event();
  e->set_t_s(t);
  e->set_kind(kind);
  e->set_agent(agent);
  e->set_detail(detail);
  return r;
}

// ---- JSON ----

TEST(JsonWriter, EscapesTextFromTheNetworkAndWritesNoNonFiniteNumber) {
  std::string out;
  JsonWriter w(out);
  w.raw("[").str("a\"b\\c\n\x01").raw(",").num(std::nan("")).raw(",").num(1.5000).raw(",");
  w.num(-0.00001, 3).raw(",").sig(1e-9).raw(",").num(1e300).raw(",").num(-2.0).raw("]");
  EXPECT_EQ(out, "[\"a\\\"b\\\\c\\u000a\\u0001\",null,1.5,0,1e-09,1e+300,-2]");
}

// Text that reaches a viewer is UTF-8, whatever it was: a byte that is not (a scenario's name, a
// run directory's path, a refusal cut at 40 bytes inside a character) becomes U+FFFD, and
// well-formed text, multi-byte characters included, passes unchanged.
TEST(JsonWriter, WritesValidUtf8WhateverItIsGiven) {
  std::string out;
  JsonWriter w(out);
  const std::string cut = std::string("caf\xC3\xA9 ") + std::string("\xE2\x82\xAC").substr(0, 2);
  w.str("bad\377").raw(",").str(cut).raw(",").str("\xED\xA0\x80").raw(",").str("\xC0\xAF");
  w.raw(",").str("\xF0\x9F\x9A\x81 ok");
  EXPECT_EQ(out,
            "\"bad\xEF\xBF\xBD\",\"caf\xC3\xA9 \xEF\xBF\xBD\xEF\xBF\xBD\","
            "\"\xEF\xBF\xBD\xEF\xBF\xBD\xEF\xBF\xBD\",\"\xEF\xBF\xBD\xEF\xBF\xBD\","
            "\"\xF0\x9F\x9A\x81 ok\"");
  EXPECT_TRUE(valid_utf8(out));
}

// ---- Foxglove's protocol ----

TEST(FoxgloveProtocol, ChoosesOneOfItsSubprotocolsFromTheClientsList) {
  EXPECT_EQ(choose_subprotocol("foxglove.websocket.v1"), "foxglove.websocket.v1");
  EXPECT_EQ(choose_subprotocol("foxglove.sdk.v1, foxglove.websocket.v1"), "foxglove.sdk.v1");
  EXPECT_EQ(choose_subprotocol("chat,  foxglove.websocket.v1 "), "foxglove.websocket.v1");
  EXPECT_EQ(choose_subprotocol(""), "");
  EXPECT_EQ(choose_subprotocol("foxglove.websocket.v2,xfoxglove.websocket.v1"), "");
}

TEST(FoxgloveProtocol, MessageFrameIsOpcodeSubscriptionTimeThenPayload) {
  const std::string f = message_frame(0x01020304u, 0x1122334455667788ull, "xy");
  ASSERT_EQ(f.size(), 15u);
  EXPECT_EQ(f[0], '\x01');
  EXPECT_EQ(f.substr(1, 4), std::string("\x04\x03\x02\x01", 4));
  EXPECT_EQ(f.substr(5, 8), std::string("\x88\x77\x66\x55\x44\x33\x22\x11", 8));
  EXPECT_EQ(f.substr(13), "xy");
  EXPECT_EQ(base64_encode(""), "");
  EXPECT_EQ(base64_encode("f"), "Zg==");
  EXPECT_EQ(base64_encode("fo"), "Zm8=");
  EXPECT_EQ(base64_encode("foobar"), "Zm9vYmFy");
}

TEST(FoxgloveProtocol, AdvertisesTheCataloguesSchemasProtobufInBase64) {
  const std::vector<FoxgloveChannel> channels = view_channels();
  ASSERT_EQ(channels.size(), 5u);
  const FoxgloveChannel& c = channels[1];
  ASSERT_EQ(c.id, kSampleChannel);
  // The schema as advertised, decoded back: a FileDescriptorSet.
  std::string bytes;
  {
    static const std::string kAlphabet =
        "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::uint32_t acc = 0;
    int bits = 0;
    for (const char ch : c.schema) {
      if (ch == '=') break;
      acc = (acc << 6) | static_cast<std::uint32_t>(kAlphabet.find(ch));
      bits += 6;
      if (bits >= 8) {
        bits -= 8;
        bytes += static_cast<char>((acc >> bits) & 0xff);
      }
    }
  }
  google::protobuf::FileDescriptorSet set;
  ASSERT_TRUE(set.ParseFromString(bytes));
  // records.proto imports struct.proto and scenario.proto: dependencies first, the type's file
  // last, as protoc --include_imports writes them.
  ASSERT_GE(set.file_size(), 3);
  EXPECT_EQ(set.file(set.file_size() - 1).name(), "records.proto");
  const std::string adv = advertise_json(channels);
  EXPECT_NE(adv.find("\"topic\":\"/swarm/agents\""), std::string::npos);
  EXPECT_NE(adv.find("\"schemaName\":\"foxglove.SceneUpdate\""), std::string::npos);
  EXPECT_NE(adv.find("\"schemaName\":\"qswarm.records.AgentSample\""), std::string::npos);
  EXPECT_NE(adv.find("\"schemaEncoding\":\"protobuf\""), std::string::npos);
}

TEST(FoxgloveProtocol, SubscribesUnsubscribesAndRefusesWhatItDoesNotServe) {
  const std::vector<FoxgloveChannel> channels = view_channels();
  FoxgloveSession s(channels, 3);
  auto o = s.handle_text(R"({"op":"subscribe","subscriptions":[{"id":7,"channelId":2}]})");
  EXPECT_FALSE(o.malformed);
  EXPECT_EQ(o.subscribed, std::vector<std::uint32_t>{2});
  EXPECT_EQ(s.subscription(2), 7u);
  // The same id twice, the same channel twice, a channel that does not exist.
  o = s.handle_text(R"({"op":"subscribe","subscriptions":[{"id":7,"channelId":3},
                      {"id":8,"channelId":2},{"id":9,"channelId":99}]})");
  EXPECT_TRUE(o.subscribed.empty());
  EXPECT_EQ(o.refusals.size(), 3u);
  // At most three subscriptions.
  o = s.handle_text(R"({"op":"subscribe","subscriptions":[{"id":1,"channelId":1},
                      {"id":3,"channelId":3},{"id":4,"channelId":4}]})");
  EXPECT_EQ(o.subscribed.size(), 2u);
  EXPECT_EQ(o.refusals.size(), 1u);
  o = s.handle_text(R"({"op":"unsubscribe","subscriptionIds":[7, 70]})");
  EXPECT_FALSE(s.subscription(2));
  EXPECT_EQ(o.refusals.size(), 1u);
  // Publishing, parameters, services: this server only publishes.
  o = s.handle_text(R"({"op":"advertise","channels":[{"id":1,"topic":"/cmd"}]})");
  EXPECT_EQ(o.refusals.size(), 1u);
  o = s.handle_text(R"({"op":"setParameters","parameters":[]})");
  EXPECT_EQ(o.refusals.size(), 1u);
}

TEST(FoxgloveProtocol, MalformedFramesAreSaidSo) {
  const std::vector<FoxgloveChannel> channels = view_channels();
  FoxgloveSession s(channels);
  for (const char* bad :
       {"", "not json", "[1,2]", "{}", "{\"op\":5}", "{\"op\":\"subscribe\",\"subscriptions\":7}",
        R"({"op":"subscribe","subscriptions":[{"id":-1,"channelId":1}]})",
        R"({"op":"subscribe","subscriptions":[{"id":1.5,"channelId":1}]})",
        R"({"op":"subscribe","subscriptions":[{"id":1e30,"channelId":1}]})",
        "{\"op\":\"subscribe\"", "\xff\xfe"}) {
    EXPECT_TRUE(s.handle_text(bad).malformed) << bad;
  }
  EXPECT_EQ(s.subscriptions(), 0u);
}

// ---- the feed and the model ----

TEST(ViewFeed, KeepsEachAgentsNewestSampleAndBoundsTheRest) {
  ViewFeed feed({2, 3, 2});
  for (int k = 0; k < 10; ++k) feed.on_record(sample_record(1, 0.1 * k), 1000 + k);
  feed.on_record(sample_record(2, 0.5), 5);
  feed.on_record(sample_record(3, 0.5), 5);  // a third id over max_agents = 2: dropped
  for (int k = 0; k < 5; ++k) feed.on_record(graph_record(0.1 * k, 3, 1.0 + k), 0);
  for (int k = 0; k < 4; ++k) feed.on_record(event_record(0.1 * k, "join", 1), 0);
  ViewBatch b = feed.take();
  ASSERT_EQ(b.samples.size(), 2u);
  EXPECT_DOUBLE_EQ(b.samples[0].sample.stamp_s(), 0.9);
  EXPECT_EQ(b.samples[0].published_wall_ns, 1009);
  ASSERT_EQ(b.graphs.size(), 3u);  // the oldest two went
  EXPECT_DOUBLE_EQ(b.graphs.front().lambda2(), 3.0);
  EXPECT_EQ(b.events.size(), 2u);
  EXPECT_EQ(feed.counts().records, 21u);
  EXPECT_EQ(feed.counts().dropped, 1u + 2u + 2u);
  EXPECT_TRUE(feed.take().empty());
}

TEST(ViewModel, FramesCarryTheChangeAndSnapshotsEverything) {
  RunConfig rc;
  rc.name = "four \"quoted\"";
  for (std::uint32_t id = 1; id <= 4; ++id) {
    AgentSpec a;
    a.id = id;
    a.position_W = Vec3(id, 0, 10);
    rc.agents.push_back(a);
  }
  ViewModel m(run_info_json(rc));
  ViewFeed feed;
  for (std::uint32_t id = 1; id <= 4; ++id) feed.on_record(sample_record(id, 1.0), 42'000'000);
  feed.on_record(graph_record(1.0, 4, 0.5), 0);
  feed.on_record(event_record(1.0, "depart", 3, "silent"), 0);
  ViewBatch b = feed.take();
  m.apply(b);
  const std::string frame = m.frame_json(b, 43'000'000);
  EXPECT_NE(frame.find("\"type\":\"frame\""), std::string::npos);
  EXPECT_NE(frame.find("\"pub_ms\":42"), std::string::npos);
  EXPECT_NE(frame.find("[3,[3,2,10],[1,0,0,0],[3,2,10],false,1]"), std::string::npos) << frame;
  EXPECT_NE(frame.find("\"edges\":[[1,2,0.5],[2,3,1],[3,4,1.5]]"), std::string::npos) << frame;
  const std::string snap = m.snapshot_json();
  EXPECT_NE(snap.find("\"name\":\"four \\\"quoted\\\"\""), std::string::npos);
  EXPECT_NE(snap.find("\"initial_average\":[2.5,0,10]"), std::string::npos) << snap;
  EXPECT_NE(snap.find("\"summary\":null"), std::string::npos);
  records::Summary sum;
  sum.set_converged(true);
  feed.on_summary(sum);
  b = feed.take();
  m.apply(b);
  EXPECT_TRUE(m.ended());
  EXPECT_NE(m.frame_json(b, 0).find("\"converged\": true"), std::string::npos);
}

TEST(ViewModel, HistoryThinsItselfInsteadOfGrowingWithoutBound) {
  ViewModel m("{}");
  for (int k = 0; k < 100'000; ++k) {
    ViewBatch b;
    b.graphs.push_back(graph_record(0.1 * k, 2, 1.0).graph());
    m.apply(b);
  }
  EXPECT_LT(m.history_size(), ViewModel::kMaxHistory);
  EXPECT_GT(m.history_size(), ViewModel::kMaxHistory / 4);
  EXPECT_NEAR(m.time_s(), 9999.9, 1e-6);
}

// ---- replay ----

class ReplayTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("qswarm-view-replay-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    std::ofstream(dir_ / "scenario.txtpb")
        << "name: \"replayed\"\nagents { id: 1 position { x: 0 y: 0 z: 10 } }\n"
           "agents { id: 2 position { x: 4 y: 0 z: 10 } }\nduration_s: 10\n";
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  // Ten simulated seconds: samples at 10 Hz per agent, a graph every 0.1 s, events.
  void record(bool with_summary) {
    RecordSinks sinks{RunDir(dir_.string()), SceneSettings{}};
    for (int k = 0; k <= 100; ++k) {
      const double t = 0.1 * k;
      for (std::uint32_t id = 1; id <= 2; ++id) {
        StateMessage s;
        s.view.id = id;
        s.stamp_s = t;
        s.p_W = Vec3(t, id, 10);
        sinks.sample(s, 1.0);
      }
      sinks.graph(graph_record(t, 2, 1.0 + t).graph());
      if (k == 30) sinks.event(t, "cut", 1, "link 1-2 cut");
      if (k == 50) sinks.event(t, "cut_end", 1, "link 1-2 restored");
    }
    ASSERT_TRUE(sinks.flush());
    if (with_summary) std::ofstream(dir_ / "summary.json") << R"({"converged": true})";
  }
  std::filesystem::path dir_;
};

TEST_F(ReplayTest, PlaysAtItsSpeedPausesSeeksAndEndsWithTheSummary) {
  record(true);
  const ReplayRun run = load_replay(dir_);
  EXPECT_EQ(run.records.size(), 101u * 3 + 2);
  EXPECT_TRUE(run.note.empty()) << run.note;
  ReplayPlayback p(run, 2.0);
  EXPECT_DOUBLE_EQ(p.duration_s(), 10.0);
  bool reset = false;
  ViewBatch b = p.advance(100.0, reset);  // the first call starts the clock at t = 0
  EXPECT_FALSE(reset);
  EXPECT_EQ(b.graphs.size(), 1u);
  b = p.advance(101.0, reset);  // one wall second at 2x: up to t = 2
  EXPECT_EQ(b.graphs.size(), 20u);
  EXPECT_EQ(b.samples.size(), 2u);
  EXPECT_DOUBLE_EQ(b.samples[0].sample.stamp_s(), 2.0);
  view::ClientOp op;
  op.set_action("pause");
  EXPECT_EQ(p.control(op, 101.0), "");
  EXPECT_TRUE(p.advance(105.0, reset).empty());
  op.set_action("seek");
  op.set_t_s(1.0);  // back: the view forgets and gets the run up to t = 1
  EXPECT_EQ(p.control(op, 105.0), "");
  b = p.advance(105.0, reset);
  EXPECT_TRUE(reset);
  EXPECT_EQ(b.graphs.size(), 11u);
  op.set_t_s(6.0);  // forward: what lies between, the cut window among it
  EXPECT_EQ(p.control(op, 105.0), "");
  b = p.advance(105.0, reset);
  EXPECT_FALSE(reset);
  EXPECT_EQ(b.events.size(), 2u);
  op.set_action("play");
  EXPECT_EQ(p.control(op, 105.0), "");
  b = p.advance(200.0, reset);  // past the end: the rest and the summary, then paused
  ASSERT_TRUE(b.summary);
  EXPECT_TRUE(b.summary->converged());
  EXPECT_DOUBLE_EQ(p.time_s(), 10.0);
  EXPECT_NE(p.state_json().find("\"playing\":false"), std::string::npos);
}

TEST_F(ReplayTest, RefusesBadControlsAndSaysWhatIsOddAboutTheRecord) {
  record(false);
  // A run cut short mid-record: half a record at the end of records.pb.
  {
    std::ofstream f(dir_ / "records.pb", std::ios::app | std::ios::binary);
    f << '\x40' << "half";
  }
  const ReplayRun run = load_replay(dir_);
  EXPECT_EQ(run.records.size(), 101u * 3 + 2);
  EXPECT_NE(run.note.find("records.pb: cut inside a record"), std::string::npos) << run.note;
  ReplayPlayback p(run, 1.0);
  view::ClientOp op;
  op.set_action("seek");
  EXPECT_NE(p.control(op, 0.0), "");  // no t
  op.set_t_s(std::nan(""));
  EXPECT_NE(p.control(op, 0.0), "");
  op.set_t_s(-1.0);
  EXPECT_NE(p.control(op, 0.0), "");
  op.set_action("speed");
  for (double bad : {0.0, -1.0, std::nan(""), 1e9}) {
    op.set_speed(bad);
    EXPECT_NE(p.control(op, 0.0), "") << bad;
  }
  op.set_action("launch");
  EXPECT_NE(p.control(op, 0.0), "");
}

// A record appended to records.pb as the recorder frames it (a varint length, then the bytes).
void append_record(const std::filesystem::path& file, const records::Record& r) {
  std::string bytes = r.SerializeAsString(), framed;
  for (std::size_t n = bytes.size();; n >>= 7) {
    framed += static_cast<char>((n & 0x7f) | (n > 0x7f ? 0x80 : 0));
    if (n <= 0x7f) break;
  }
  std::ofstream(file, std::ios::app | std::ios::binary) << framed << bytes;
}

// What a careless user or an attacker hands over as records.pb never becomes records: zeros stop
// the reading at once (not four million empty records), a FIFO or /dev/zero is refused without
// blocking, and a record whose time is not a run's ends what is played, said in the note.
TEST_F(ReplayTest, ZerosAFifoDevZeroOrAnImpossibleTimeAreNeverPlayed) {
  namespace fs = std::filesystem;
  record(false);
  const fs::path records = dir_ / "records.pb";
  const std::string good = [&] {
    std::ifstream in(records, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }();
  std::ofstream(records, std::ios::app | std::ios::binary) << std::string(4u << 20, '\0');
  ReplayRun run = load_replay(dir_);
  EXPECT_EQ(run.records.size(), 101u * 3 + 2);
  EXPECT_NE(run.note.find("a record holds nothing"), std::string::npos) << run.note;
  std::ofstream(records, std::ios::trunc | std::ios::binary) << std::string(4u << 20, '\0');
  EXPECT_THROW(load_replay(dir_), ReplayError);
  for (const bool fifo : {true, false}) {
    fs::remove(records);
    if (fifo)
      ASSERT_EQ(::mkfifo(records.c_str(), 0600), 0);
    else
      fs::create_symlink("/dev/zero", records);
    try {
      load_replay(dir_);
      ADD_FAILURE() << "a " << (fifo ? "FIFO" : "link to /dev/zero") << " was replayed";
    } catch (const ReplayError& e) {
      EXPECT_NE(std::string(e.what()).find("not a regular file"), std::string::npos) << e.what();
    }
  }
  // A summary.json that is a FIFO is no summary (and is never opened).
  fs::remove(records);
  std::ofstream(records, std::ios::binary) << good;
  ASSERT_EQ(::mkfifo((dir_ / "summary.json").c_str(), 0600), 0);
  run = load_replay(dir_);
  EXPECT_FALSE(run.summary.has_value());
  for (const double t : {std::nan(""), 1e300, -100.0}) {
    std::ofstream(records, std::ios::trunc | std::ios::binary) << good;
    records::Record bad;
    bad.mutable_event()->set_t_s(t);
    bad.mutable_event()->set_kind("cut");
    append_record(records, bad);
    run = load_replay(dir_);
    EXPECT_EQ(run.records.size(), 101u * 3 + 2) << t;
    EXPECT_NE(run.note.find("a record's time is not a run's time"), std::string::npos) << run.note;
    EXPECT_DOUBLE_EQ(ReplayPlayback(run, 1.0).duration_s(), 10.0) << t;
  }
}

TEST_F(ReplayTest, RefusesADirectoryWithoutARecord) {
  EXPECT_THROW(load_replay(dir_ / "nope"), ReplayError);
  EXPECT_THROW(load_replay(dir_), ReplayError);  // no records.pb
  std::ofstream(dir_ / "records.pb");
  try {
    load_replay(dir_);
    FAIL() << "an empty records.pb was accepted";
  } catch (const ReplayError& e) {
    EXPECT_NE(std::string(e.what()).find("no records"), std::string::npos);
  }
}

// ---- the server, over real sockets on loopback ----

// A Foxglove client as the page is one: it connects with the sub-protocol, reads serverInfo and
// advertise, and subscribes. Its socket lives on a thread of its own (one io_context thread: reads
// and writes never race); what it reads waits in a queue.
class Client {
 public:
  explicit Client(std::uint16_t port, const std::string& proto = "foxglove.websocket.v1")
      : ws_(ioc_) {
    tcp::resolver r(ioc_);
    asio::connect(ws_.next_layer(), r.resolve("127.0.0.1", std::to_string(port)));
    ws_.set_option(websocket::stream_base::decorator([proto](websocket::request_type& req) {
      req.set(http::field::sec_websocket_protocol, proto);
    }));
    ws_.handshake("127.0.0.1", "/");  // throws when refused
    ws_.read_message_max(64u << 20);
    read_next();
    thread_ = std::thread([this] { ioc_.run(); });
  }
  ~Client() {
    asio::post(ioc_, [this] {
      beast::error_code ec;
      ws_.next_layer().close(ec);
    });
    work_.reset();
    thread_.join();
  }
  // The next message; "" when none comes within `timeout_s` or the connection ended.
  std::string read(double timeout_s = 5.0, bool* binary = nullptr) {
    std::unique_lock<std::mutex> lock(mu_);
    cv_.wait_for(lock, std::chrono::microseconds(static_cast<std::int64_t>(timeout_s * 1e6)),
                 [this] { return !in_.empty() || ended_; });
    if (in_.empty()) return "";
    auto [bin, m] = std::move(in_.front());
    in_.pop_front();
    if (binary) *binary = bin;
    return m;
  }
  // Throws when the connection is gone.
  void send(const std::string& text) {
    std::promise<beast::error_code> done;
    asio::post(ioc_, [&] {
      ws_.text(true);
      ws_.async_write(asio::buffer(text),
                      [&](beast::error_code ec, std::size_t) { done.set_value(ec); });
    });
    const beast::error_code ec = done.get_future().get();
    if (ec) throw beast::system_error(ec);
  }
  // Reads until a message on a channel whose JSON contains `needle`.
  std::string await_view(const std::string& needle, double timeout_s = 10.0) {
    const auto until = std::chrono::steady_clock::now() +
                       std::chrono::milliseconds(static_cast<int>(timeout_s * 1000));
    while (std::chrono::steady_clock::now() < until) {
      bool bin = false;
      const std::string m = read(0.5, &bin);
      if (bin && m.size() > 13 && m[0] == '\x01' && m.find(needle, 13) != std::string::npos)
        return m.substr(13);
    }
    return "";
  }

 private:
  void read_next() {
    ws_.async_read(buf_, [this](beast::error_code ec, std::size_t) {
      std::lock_guard<std::mutex> lock(mu_);
      if (ec) {
        ended_ = true;
        cv_.notify_all();
        return;
      }
      in_.emplace_back(ws_.got_binary(), beast::buffers_to_string(buf_.data()));
      buf_.consume(buf_.size());
      cv_.notify_all();
      read_next();
    });
  }
  asio::io_context ioc_;
  std::optional<asio::executor_work_guard<asio::io_context::executor_type>> work_{
      asio::make_work_guard(ioc_)};
  websocket::stream<tcp::socket> ws_;
  beast::flat_buffer buf_;
  std::thread thread_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<std::pair<bool, std::string>> in_;
  bool ended_ = false;
};

// Polls `pred` until it holds or `timeout_s` passed.
bool eventually(const std::function<bool()>& pred, double timeout_s = 10.0) {
  const auto until = std::chrono::steady_clock::now() +
                     std::chrono::milliseconds(static_cast<int>(timeout_s * 1000));
  while (std::chrono::steady_clock::now() < until) {
    if (pred()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return pred();
}

std::string http_get(std::uint16_t port, const std::string& target, int* status = nullptr,
                     const std::string& host = "127.0.0.1") {
  asio::io_context ioc;
  beast::tcp_stream s(ioc);
  tcp::resolver r(ioc);
  s.connect(r.resolve("127.0.0.1", std::to_string(port)));
  http::request<http::empty_body> req{http::verb::get, target, 11};
  req.set(http::field::host, host);
  http::write(s, req);
  beast::flat_buffer b;
  http::response<http::string_body> res;
  http::read(s, b, res);
  if (status) *status = res.result_int();
  return res.body();
}

class ViewServerTest : public ::testing::Test {
 protected:
  ViewServerOptions options() {
    ViewServerOptions o;
    o.port = 0;
    o.page_dir = QSWARM_SOURCE_DIR "/common/view/page";
    o.frame_period_s = 0.02;
    o.log = [this](const std::string& s) {
      std::lock_guard<std::mutex> lock(log_mu_);
      log_.push_back(s);
    };
    return o;
  }
  // A frame's worth of a swarm of n agents at simulated time t, as the recorder would write it.
  void feed_swarm(ViewFeed& feed, int n, double t) {
    for (int id = 1; id <= n; ++id)
      feed.on_record(sample_record(static_cast<std::uint32_t>(id), t, t), 0);
    feed.on_record(graph_record(t, n, 1.0 + t), 0);
  }
  std::mutex log_mu_;
  std::vector<std::string> log_;
};

TEST_F(ViewServerTest, ServesThePageAndOnlyItsFilesOverHttp) {
  ViewFeed feed;
  ViewServer server(options(), feed, "{}", SceneSettings{});
  server.start();
  int status = 0;
  EXPECT_NE(http_get(server.port(), "/", &status).find("quadswarm live view"), std::string::npos);
  EXPECT_EQ(status, 200);
  http_get(server.port(), "/view.js?x=1", &status);
  EXPECT_EQ(status, 200);
  for (const char* t :
       {"/../CMakeLists.txt", "/etc/passwd", "/view.js/../../x", "/lib/", "/%2e%2e/README.md"}) {
    http_get(server.port(), t, &status);
    EXPECT_EQ(status, 404) << t;
  }
  EXPECT_NE(http_get(server.port(), "/stats", &status).find("\"not_found\":5"), std::string::npos);
  // A site's name that points at this host (DNS rebinding) is refused; addresses and localhost
  // are served.
  for (const char* host : {"localhost", "127.0.0.1:8765", "[::1]:8765", "localhost:1"}) {
    http_get(server.port(), "/", &status, host);
    EXPECT_EQ(status, 200) << host;
  }
  for (const char* host : {"evil.example", "evil.example:8765", "127.0.0.1.evil.example", "[::1"}) {
    http_get(server.port(), "/", &status, host);
    EXPECT_EQ(status, 403) << host;
  }
  EXPECT_EQ(server.counts().refused_hosts, 4u);
  // Listening on loopback written as IPv6 (::ffff:127.0.0.1) keeps the Host check.
  ViewServerOptions mapped = options();
  mapped.address = "::ffff:127.0.0.1";
  ViewServer other(mapped, feed, "{}", SceneSettings{});
  other.start();
  http_get(other.port(), "/", &status, "evil.example");
  EXPECT_EQ(status, 403);
  http_get(other.port(), "/", &status, "localhost");
  EXPECT_EQ(status, 200);
  // A multicast group is no address to listen on.
  EXPECT_NE(probe_listen("239.1.2.3", 0).find("multicast"), std::string::npos);
  ViewServerOptions group = options();
  group.address = "ff02::1";
  EXPECT_THROW(ViewServer(group, feed, "{}", SceneSettings{}).start(), ViewServerError);
}

TEST_F(ViewServerTest, APageGetsASnapshotThenFramesAndTheEnd) {
  ViewFeed feed;
  ViewServer server(options(), feed, R"({"name":"t"})", SceneSettings{});
  server.start();
  Client c(server.port());
  const std::string info = c.read();
  EXPECT_NE(info.find("\"op\":\"serverInfo\""), std::string::npos) << info;
  EXPECT_NE(c.read().find("\"op\":\"advertise\""), std::string::npos);
  feed_swarm(feed, 4, 1.0);
  c.send(R"({"op":"subscribe","subscriptions":[{"id":5,"channelId":1}]})");
  EXPECT_NE(c.await_view("\"type\":\"snapshot\"").find("\"run\":{\"name\":\"t\"}"),
            std::string::npos);
  feed_swarm(feed, 4, 2.0);
  // The frame after t = 2's graph (lambda2 = 1 + t): one built between its samples and its graph
  // has t = 2 and the graph before it.
  const std::string frame = c.await_view("\"lambda2\":3");
  EXPECT_NE(frame.find("\"t\":2,"), std::string::npos) << frame;
  records::Summary s;
  s.set_end_reason("duration");
  feed.on_summary(s);
  feed.on_record(event_record(3.0, "end", 0, "duration"), 0);
  EXPECT_NE(c.await_view("\"end_reason\": \"duration\"").find("\"kind\":\"end\""),
            std::string::npos);
  // The live view is read-only: a playback control is refused.
  c.send(R"({"op":"qswarmPlayback","action":"pause"})");
  std::string m;
  while (!(m = c.read(2.0)).empty() && m.find("\"op\":\"status\"") == std::string::npos) {
  }
  EXPECT_NE(m.find("read-only"), std::string::npos) << m;
  EXPECT_EQ(server.counts().refused_ops, 1u);
}

TEST_F(ViewServerTest, ProtobufChannelsCarryTheRecordsMessages) {
  ViewFeed feed;
  ViewServer server(options(), feed, "{}", SceneSettings{});
  server.start();
  Client c(server.port(), "chat, foxglove.sdk.v1");
  c.read();
  c.read();
  c.send(R"({"op":"subscribe","subscriptions":[{"id":9,"channelId":2},{"id":10,"channelId":5}]})");
  feed_swarm(feed, 3, 1.5);
  std::string scene;
  std::set<std::uint32_t> ids;
  for (int k = 0; k < 50 && ids.size() < 3; ++k) {
    bool bin = false;
    const std::string m = c.read(1.0, &bin);
    if (!bin || m.size() < 13) continue;
    std::uint32_t sub = 0;
    std::memcpy(&sub, m.data() + 1, 4);
    std::uint64_t t_ns = 0;
    std::memcpy(&t_ns, m.data() + 5, 8);
    EXPECT_EQ(t_ns, 1'500'000'000u);  // the record's simulated time
    if (sub == 10) {                  // the 3D scene of the snapshot
      scene = m.substr(13);
      continue;
    }
    EXPECT_EQ(sub, 9u);
    records::AgentSample s;
    ASSERT_TRUE(s.ParseFromString(m.substr(13)));
    ids.insert(s.id());
  }
  EXPECT_EQ(ids, (std::set<std::uint32_t>{1, 2, 3}));
  if (scene.empty()) scene = c.await_view("entities");
  EXPECT_NE(scene.find("\"agent/3\""), std::string::npos) << scene.substr(0, 300);
  EXPECT_NE(scene.find("\"links\""), std::string::npos);
}

TEST_F(ViewServerTest, AClientThatNeverReadsLosesFramesNotTheOthers) {
  ViewServerOptions o = options();
  // Room for two frames of 512 samples (the queue counts messages): a client that reads each
  // frame before the next comes never fills it, one that never reads does within a few frames.
  o.max_queue_frames = 1100;
  ViewFeed feed;
  ViewServer server(o, feed, "{}", SceneSettings{});
  server.start();
  const std::string both =
      R"({"op":"subscribe","subscriptions":[{"id":1,"channelId":1},{"id":2,"channelId":2}]})";
  Client good(server.port());
  good.read();
  good.read();
  good.send(both);
  // Subscribed to both once the view's snapshot comes (the same request subscribes both).
  ASSERT_FALSE(good.await_view("\"type\":\"snapshot\"").empty());
  // Reads until frame k's view and all its 512 samples (subscription 2, counted by their stamp)
  // have come: the server may take a frame in two batches, and the feed keeps only each agent's
  // newest sample, so the next frame is fed only once this one is wholly sent.
  std::map<std::uint64_t, int> samples_at;
  auto await_frame = [&](int k) {
    const std::string needle = "\"t\":" + std::to_string(k) + ",";
    bool view = false;
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (std::chrono::steady_clock::now() < until) {
      if (view && samples_at[static_cast<std::uint64_t>(k)] == 512) return true;
      bool bin = false;
      const std::string m = good.read(0.5, &bin);
      if (!bin || m.size() < 13 || m[0] != '\x01') continue;
      std::uint32_t sub = 0;
      std::memcpy(&sub, m.data() + 1, 4);
      std::uint64_t t_ns = 0;
      std::memcpy(&t_ns, m.data() + 5, 8);
      if (sub == 2) ++samples_at[t_ns / 1'000'000'000u];
      if (sub == 1 && m.find(needle, 13) != std::string::npos) view = true;
    }
    return false;
  };
  // 512 agents a frame: about 60 kB of JSON and 512 protobuf messages. The next frame comes
  // once the good client has read this one, so how fast this process runs does not matter.
  int frames = 0;
  auto fly = [&](int from, int to) {
    for (int k = from; k <= to; ++k) {
      feed_swarm(feed, 512, k);
      if (!await_frame(k)) return;  // stuck too
      ++frames;
    }
  };
  // Alone, a client that reads what it subscribed to loses nothing under these limits.
  fly(1, 5);
  EXPECT_EQ(server.counts().frames_dropped, 0u);
  // The stuck client: a real WebSocket with the same subscriptions, which then never reads
  // again (its receive buffer kept small, so the server's socket fills soon).
  asio::io_context ioc;
  websocket::stream<tcp::socket> stuck(ioc);
  stuck.next_layer().open(tcp::v4());
  stuck.next_layer().set_option(asio::socket_base::receive_buffer_size(4096));
  stuck.next_layer().connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), server.port()));
  stuck.set_option(websocket::stream_base::decorator([](websocket::request_type& r) {
    r.set(http::field::sec_websocket_protocol, "foxglove.websocket.v1");
  }));
  stuck.handshake("127.0.0.1", "/");
  stuck.write(asio::buffer(both));
  fly(6, 60);
  EXPECT_EQ(frames, 60);  // every one, while the stuck client lost some of its
  EXPECT_GT(server.counts().frames_dropped, 0u);
  for (std::uint64_t k = 1; k <= 60; ++k) EXPECT_EQ(samples_at[k], 512) << "frame " << k;
  std::lock_guard<std::mutex> lock(log_mu_);
  EXPECT_EQ(
      std::count_if(log_.begin(), log_.end(),
                    [](const std::string& s) { return s.find("keeping up") != std::string::npos; }),
      1);  // said once, counted always
}

TEST_F(ViewServerTest, MalformedOversizedAndFloodingClientsAreRefusedAndCounted) {
  ViewServerOptions o = options();
  o.max_message_bytes = 4096;
  o.client_messages_per_s = 20;
  o.strikes = 30;
  ViewFeed feed;
  ViewServer server(o, feed, "{}", SceneSettings{});
  server.start();
  Client good(server.port());
  good.read();
  good.read();
  good.send(R"({"op":"subscribe","subscriptions":[{"id":1,"channelId":1}]})");
  {
    Client bad(server.port());
    bad.send("{\"op\":");
    bad.send("\x01\x02 not json");
    bad.send(R"({"op":"subscribe","subscriptions":[{"id":-3,"channelId":1}]})");
    EXPECT_TRUE(eventually([&] { return server.counts().malformed == 3; }));
  }
  {
    // Text that is not UTF-8 breaks the WebSocket protocol itself: the session ends, counted.
    Client broken(server.port());
    broken.send("{\"op\":\"\xff\xfe\"}");
    EXPECT_TRUE(eventually([&] { return server.counts().malformed == 4; }));
  }
  {
    Client big(server.port());
    big.send(std::string(5000, ' ') + "{}");
    EXPECT_TRUE(eventually([&] { return server.counts().oversized == 1; }));
  }
  {
    // A flood of subscribe requests: the rate refuses the excess, strikes close the session.
    Client flood(server.port());
    for (int k = 0; k < 400; ++k) {
      beast::error_code ec;
      try {
        flood.send(R"({"op":"subscribe","subscriptions":[{"id":)" + std::to_string(k) +
                   R"(,"channelId":1}]})");
      } catch (const std::exception&) {
        break;  // closed on us
      }
    }
    EXPECT_TRUE(eventually([&] { return server.counts().closed_for_abuse == 1; }));
    EXPECT_GT(server.counts().flooded, 0u);
  }
  // A WebSocket without our sub-protocol is refused at the handshake.
  EXPECT_THROW(Client(server.port(), "chat"), std::exception);
  EXPECT_EQ(server.counts().refused_upgrades, 1u);
  // Through all of it the good client kept its session.
  feed_swarm(feed, 2, 7.0);
  EXPECT_FALSE(good.await_view("\"t\":7,").empty());
}

TEST_F(ViewServerTest, ManyConnectionsAreCappedAndTheServerStaysUsable) {
  ViewServerOptions o = options();
  o.max_connections = 16;
  ViewFeed feed;
  ViewServer server(o, feed, "{}", SceneSettings{});
  server.start();
  asio::io_context ioc;
  std::vector<tcp::socket> held;
  for (int k = 0; k < 40; ++k) {
    held.emplace_back(ioc);
    held.back().connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), server.port()));
  }
  // Past the limit each new connection takes the place of the oldest that sent no request.
  EXPECT_TRUE(eventually([&] { return server.counts().evicted >= 24; }));
  EXPECT_EQ(server.counts().refused_connections, 0u);
  held.clear();
  EXPECT_TRUE(eventually([&] {
    try {
      return http_get(server.port(), "/").find("quadswarm") != std::string::npos;
    } catch (const std::exception&) {
      return false;
    }
  }));
}

// 64 WebSockets that subscribe to nothing and 200 connections that never send a request, all held
// open from this host: a new viewer still gets the page, subscribes and gets its frames, and the
// server says what it closed. Sessions that subscribed and read are never closed for another.
TEST_F(ViewServerTest, HeldSocketsNeverKeepANewViewerOut) {
  ViewFeed feed;
  ViewServer server(options(), feed, "{}", SceneSettings{});
  server.start();
  std::vector<std::unique_ptr<Client>> idle;
  for (int k = 0; k < 64; ++k) idle.push_back(std::make_unique<Client>(server.port()));
  asio::io_context ioc;
  std::vector<tcp::socket> half_open;
  for (int k = 0; k < 200; ++k) {
    half_open.emplace_back(ioc);
    half_open.back().connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), server.port()));
  }
  EXPECT_TRUE(eventually([&] { return server.counts().evicted >= 200; }));
  // A viewer: the page, then a session subscribed to the view channel, and frames.
  int status = 0;
  std::string page;
  EXPECT_TRUE(eventually([&] {
    try {
      page = http_get(server.port(), "/", &status);
      return status == 200;
    } catch (const std::exception&) {
      return false;
    }
  }));
  EXPECT_NE(page.find("quadswarm live view"), std::string::npos);
  Client viewer(server.port());
  ASSERT_NE(viewer.read().find("serverInfo"), std::string::npos);
  ASSERT_NE(viewer.read().find("advertise"), std::string::npos);
  viewer.send(R"({"op":"subscribe","subscriptions":[{"id":7,"channelId":1}]})");
  double t = 0.0;
  EXPECT_TRUE(eventually([&] {
    feed_swarm(feed, 3, t += 0.1);
    return !viewer.await_view("\"lambda2\"", 0.2).empty();
  }));
  // Yet more held sockets: the subscribed viewer is never the one that goes.
  for (int k = 0; k < 100; ++k) {
    half_open.emplace_back(ioc);
    half_open.back().connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), server.port()));
  }
  EXPECT_TRUE(eventually([&] { return server.counts().evicted >= 300; }));
  EXPECT_TRUE(eventually([&] {
    feed_swarm(feed, 3, t += 0.1);
    return !viewer.await_view("\"lambda2\"", 0.2).empty();
  }));
  std::lock_guard<std::mutex> lock(log_mu_);
  bool said = false;
  for (const std::string& line : log_) said |= line.find("to make room") != std::string::npos;
  EXPECT_TRUE(said);
}

// A refusal quotes at most 40 bytes of what it refuses: cut inside a character, it is still UTF-8
// (a text frame that is not would end the sender's own session), and the session goes on.
TEST_F(ViewServerTest, ARefusalCutInsideACharacterStillReachesTheClient) {
  ViewFeed feed;
  ViewServer server(options(), feed, "{}", SceneSettings{});
  server.start();
  Client c(server.port());
  c.read();
  c.read();
  c.send(R"({"op":")" + std::string(39, 'x') + "\xC3\xA9" + R"("})");
  const std::string status = c.read();
  EXPECT_NE(status.find("\"op\":\"status\""), std::string::npos) << status;
  EXPECT_TRUE(valid_utf8(status));
  c.send(R"({"op":"subscribe","subscriptions":[{"id":1,"channelId":1}]})");
  EXPECT_FALSE(c.await_view("\"type\":\"snapshot\"").empty());
}

TEST_F(ViewServerTest, APortInUseIsRefusedWithTheReason) {
  ViewFeed feed;
  ViewServer first(options(), feed, "{}", SceneSettings{});
  first.start();
  ViewServerOptions o = options();
  o.port = first.port();
  ViewServer second(o, feed, "{}", SceneSettings{});
  try {
    second.start();
    FAIL() << "a second server listened on a port in use";
  } catch (const ViewServerError& e) {
    EXPECT_NE(std::string(e.what()).find("in use"), std::string::npos) << e.what();
  }
  EXPECT_NE(probe_listen("127.0.0.1", first.port()), "");
  EXPECT_NE(probe_listen("not-an-address", 0), "");
  EXPECT_EQ(probe_listen("127.0.0.1", 0), "");
}

TEST_F(ViewServerTest, AReplayIsControlledFromThePage) {
  ReplayRun run;
  run.run_info = "{}";
  for (int k = 0; k <= 100; ++k) run.records.push_back(graph_record(0.1 * k, 2, 1.0 + k));
  ReplayPlayback playback(run, 1.0);
  ViewFeed unused;
  ViewServer server(options(), unused, run.run_info, SceneSettings{}, &playback);
  server.start();
  Client c(server.port());
  c.read();
  c.read();
  c.send(R"({"op":"subscribe","subscriptions":[{"id":1,"channelId":1}]})");
  EXPECT_NE(c.await_view("snapshot").find("\"duration\":10"), std::string::npos);
  c.send(R"({"op":"qswarmPlayback","action":"pause"})");
  EXPECT_FALSE(c.await_view("\"playing\":false").empty());
  c.send(R"({"op":"qswarmPlayback","action":"seek","t":9.5})");
  EXPECT_FALSE(c.await_view("\"lambda2\":96").empty());
  c.send(R"({"op":"qswarmPlayback","action":"seek","t":2})");
  // Back: a fresh snapshot that holds the run up to t = 2 only.
  const std::string snap = c.await_view("snapshot");
  EXPECT_NE(snap.find("\"t\":2,"), std::string::npos) << snap.substr(0, 300);
  EXPECT_EQ(snap.find("\"lambda2\":96"), std::string::npos);
  c.send(R"({"op":"qswarmPlayback","action":"speed","speed":0})");
  std::string m;
  while (!(m = c.read(2.0)).empty() && m.find("\"op\":\"status\"") == std::string::npos) {
  }
  EXPECT_NE(m.find("speed"), std::string::npos) << m;
}

}  // namespace
}  // namespace qswarm
