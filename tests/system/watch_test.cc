// Watch over real sockets, as a client in another language would use it (a raw DEALER speaking
// the wire codec): (a) a Watch sent right after Submit's reply gets the job's events and its
// final event, every time; (b) cancelling a job pushes a final "cancelled" event to its watchers;
// (c) every pushed event echoes the request_id of the Watch that registered it.
#include <gtest/gtest.h>

#include <zmq.hpp>

#include "service/wire_codec.h"
#include "tests/system/service_harness.h"

namespace pz::testing {
namespace {

using namespace std::chrono_literals;
using service::ClientReplyMsg;
using service::ClientRequestMsg;

/// A raw client: one DEALER, requests and replies in the wire codec.
class RawClient {
 public:
  explicit RawClient(const std::string& endpoint) : s_(ctx_, zmq::socket_type::dealer) {
    s_.set(zmq::sockopt::linger, 0);
    s_.connect(endpoint);
  }
  void Send(const ClientRequestMsg& r) { s_.send(zmq::buffer(service::EncodeClientRequest(r))); }
  /// The next reply or event within `timeout`; false when none came.
  bool Receive(ClientReplyMsg* m, std::chrono::milliseconds timeout) {
    zmq::pollitem_t items[] = {{s_.handle(), 0, ZMQ_POLLIN, 0}};
    zmq::poll(items, 1, timeout);
    if (!(items[0].revents & ZMQ_POLLIN)) return false;
    zmq::message_t msg;
    if (!s_.recv(msg)) return false;
    return service::DecodeClientReply(msg.to_string_view(), m).ok();
  }

 private:
  zmq::context_t ctx_;
  zmq::socket_t s_;
};

ClientRequestMsg Request(ClientRequestMsg::Type type, uint64_t id, const std::string& job = {}) {
  ClientRequestMsg r;
  r.type = type;
  r.request_id = id;
  r.job_id = job;
  return r;
}

TEST(Watch, AWatchRightAfterSubmitGetsEveryEventAndTheEnd) {
  Cluster c("watch-race");
  c.AddWorker(2);
  RawClient raw(c.client_endpoint());
  constexpr int kTries = 40;
  int complete = 0;
  for (int i = 0; i < kTries; ++i) {
    // A fresh, short job each time (5 generations of 16).
    ClientRequestMsg submit = Request(ClientRequestMsg::Type::kSubmit, 1000 + i);
    submit.spec = SyntheticSpec(100 + i, 16, 5);
    submit.client_token = "watch-race-" + std::to_string(i);
    raw.Send(submit);
    ClientReplyMsg reply;
    ASSERT_TRUE(raw.Receive(&reply, 5000ms)) << "try " << i;
    ASSERT_EQ(reply.code, service::WireCode::kOk) << reply.error;
    const std::string job = reply.job_id;
    const uint64_t watch_id = 5000 + i;
    raw.Send(Request(ClientRequestMsg::Type::kWatch, watch_id, job));  // at once
    bool answered = false, final_seen = false;
    int events = 0;
    const auto until = std::chrono::steady_clock::now() + 15s;
    while (!final_seen && std::chrono::steady_clock::now() < until) {
      ClientReplyMsg m;
      if (!raw.Receive(&m, 500ms)) continue;
      EXPECT_EQ(m.request_id, watch_id) << "try " << i << ": a reply or event for another request";
      if (m.type == ClientReplyMsg::Type::kEvent) {
        EXPECT_EQ(m.event.job_id, job);
        ++events;
        final_seen = service::IsFinal(m.event.state);
      } else {
        ASSERT_EQ(m.code, service::WireCode::kOk) << m.error;
        answered = true;
        final_seen = service::IsFinal(m.info.state);  // already over: the reply says so
        if (final_seen) ++events;
      }
    }
    EXPECT_TRUE(answered) << "try " << i;
    EXPECT_TRUE(final_seen) << "try " << i << ": no final event (" << events << " events)";
    complete += final_seen;
  }
  EXPECT_EQ(complete, kTries);
}

TEST(Watch, CancelPushesTheFinalEventToEveryWatcher) {
  Cluster c("watch-cancel");
  c.AddWorker(1);
  auto client = c.Client();
  svcclient::SubmitResult r;
  ASSERT_TRUE(client.Submit(SyntheticSpec(7, 8, 1000, /*sleep_ms=*/5), &r).ok());  // long
  RawClient w1(c.client_endpoint()), w2(c.client_endpoint());
  w1.Send(Request(ClientRequestMsg::Type::kWatch, 71, r.job_id));
  w2.Send(Request(ClientRequestMsg::Type::kWatch, 72, r.job_id));
  // Both see generations go by.
  auto first_event = [&](RawClient& w) {
    const auto until = std::chrono::steady_clock::now() + 15s;
    while (std::chrono::steady_clock::now() < until) {
      ClientReplyMsg m;
      if (w.Receive(&m, 500ms) && m.type == ClientReplyMsg::Type::kEvent) return true;
    }
    return false;
  };
  ASSERT_TRUE(first_event(w1));
  ASSERT_TRUE(first_event(w2));
  ASSERT_TRUE(client.Cancel(r.job_id).ok());
  for (auto [w, id] :
       {std::pair<RawClient*, uint64_t>{&w1, 71}, std::pair<RawClient*, uint64_t>{&w2, 72}}) {
    bool cancelled = false;
    const auto until = std::chrono::steady_clock::now() + 10s;
    while (!cancelled && std::chrono::steady_clock::now() < until) {
      ClientReplyMsg m;
      if (!w->Receive(&m, 500ms) || m.type != ClientReplyMsg::Type::kEvent) continue;
      EXPECT_EQ(m.request_id, id);
      if (service::IsFinal(m.event.state)) {
        EXPECT_EQ(m.event.state, service::JobState::kCancelled);
        cancelled = true;
      }
    }
    EXPECT_TRUE(cancelled) << "watcher " << id << " got no final event after the cancel";
  }
}

}  // namespace
}  // namespace pz::testing
