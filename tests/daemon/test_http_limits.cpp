// naneyed under hostile or careless clients (issue 13): slow and idle connections cannot starve a
// normal one, requests are bounded, parameters are parsed strictly, event-stream slots come back.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include "naneyed_fixture.hpp"
#include "raw_client.hpp"

using namespace naneye::daemon::test;

TEST_F(NaneyedTest, FiveHundredSlowConnectionsDoNotStarveANormalClient) {
  // Each connection held one of httplib's 8 pool threads while it sent its head a byte at a time:
  // 8 such clients stopped all service (/v1/status timed out at 15 s).
  // 500 client sockets here and 500 in the daemon (which inherits the limit): raise the soft limit
  // to what the hard one allows (a shell's default soft limit is often 1024).
  rlimit rl{};
  getrlimit(RLIMIT_NOFILE, &rl);
  if (rl.rlim_cur < 1200 && (rl.rlim_max == RLIM_INFINITY || rl.rlim_max >= 1200)) {
    rl.rlim_cur = 4096 < rl.rlim_max ? 4096 : rl.rlim_max;
    setrlimit(RLIMIT_NOFILE, &rl);
    getrlimit(RLIMIT_NOFILE, &rl);
  }
  if (rl.rlim_cur < 1200) GTEST_SKIP() << "needs 1200 descriptors, the hard limit is " << rl.rlim_max;
  // The slow heads get 10 s to send theirs, not the default 2 s: everything below must happen before
  // the first head's deadline (0.6-1.5 s estimated for a sanitizer build on a loaded 2-core machine).
  // This test is about starvation; the deadline has its own test below.
  start("head_timeout_ms = 10000\n" + looping_source(capture(20)));
  wait_status([](const nlohmann::json& s) { return s["pairs"]["processed"] > 1; });
  std::vector<std::unique_ptr<RawClient>> slow;
  for (int i = 0; i < 500; ++i) {
    slow.push_back(std::make_unique<RawClient>(port));
    ASSERT_TRUE(slow.back()->connected()) << i;
    ASSERT_TRUE(slow.back()->send("GET /v1/status HTTP/1.1\r\nHo")) << i;
  }
  // Still slow: another byte each, well within the head deadline.
  for (auto& s : slow) s->send("s");
  httplib::Client normal("127.0.0.1", port);
  // Starved, the answer never came (15 s and more); served, it takes milliseconds (the figure is
  // printed below, and scripts/attack.sh measures the p99). 3 s leaves room for a sanitizer build on
  // a loaded CI machine without letting starvation pass.
  normal.set_read_timeout(3, 0);
  normal.set_connection_timeout(3, 0);
  for (int k = 0; k < 20; ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    const auto r = normal.Get("/v1/status");
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    ASSERT_TRUE(r) << "request " << k << " got no answer within 3 s with 500 slow connections open";
    EXPECT_EQ(r->status, 200);
    if (k == 0) {
      const auto j = nlohmann::json::parse(r->body);
      EXPECT_GE(j["http"]["connections"].get<int>(), 500);
      std::printf("[ figures ] first /v1/status with 500 slow connections open: %.2f ms\n", ms);
    }
  }
  // Every one is in the middle of its head, and shown so (what an operator sees of a slowloris).
  wait_status([](const nlohmann::json& s) { return s["http"]["reading_heads"].get<int>() == 500; });
}

TEST_F(NaneyedTest, AHeadThatDoesNotArriveInTimeGets408AndTheConnectionCloses) {
  start("head_timeout_ms = 300\n" + looping_source(capture(12)));
  RawClient conn(port);
  ASSERT_TRUE(conn.connected());
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_TRUE(conn.send("GET /v1/status HTTP/1.1\r\n"));
  // A byte every 100 ms would have kept httplib's per-recv timeout from ever firing.
  for (int i = 0; i < 3; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    conn.send("X");
  }
  const std::string r = conn.read_all();
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(status_of(r), 408) << r;
  EXPECT_NE(r.find("\"request_timeout\""), std::string::npos) << r;
  EXPECT_LT(s, 3.0) << "the connection was not closed at its deadline";
  EXPECT_EQ(get_json("/v1/status")["http"]["head_timeouts"], 1);
}

TEST_F(NaneyedTest, OversizeRequestsAreRefusedBeforeTheyAreRead) {
  start(looping_source(capture(12)));
  struct Case {
    std::string request;
    int status;
    const char* error;
  };
  const std::string many_headers = [] {
    std::string h;
    for (int i = 0; i < 65; ++i) h += "X-" + std::to_string(i) + ": 1\r\n";
    return h;
  }();
  const std::vector<Case> cases{
      {"GET /v1/status?" + std::string(9000, 'a') + " HTTP/1.1\r\nHost: x\r\n\r\n", 414, "uri_too_long"},
      {"GET /v1/status HTTP/1.1\r\nHost: x\r\n" + many_headers + "\r\n", 431, "headers_too_large"},
      {"GET /v1/status HTTP/1.1\r\nX-Big: " + std::string(17000, 'b') + "\r\n\r\n", 431, "headers_too_large"},
      // A 1 GB body took the daemon's RSS to 1.07 GB: refused on its Content-Length alone.
      {"GET /v1/status HTTP/1.1\r\nContent-Length: 1000000000\r\n\r\n", 413, "payload_too_large"},
      {"POST /v1/status HTTP/1.1\r\nTransfer-Encoding: chunked\r\n\r\n", 411, "length_required"},
      {"GET /v1/status HTTP/1.1\r\nContent-Length: 5\r\nContent-Length: 6\r\n\r\n", 400, "bad_request"},
      {"GET /v1/status HTTP/1.1\r\nContent-Length: -1\r\n\r\n", 400, "bad_request"},
  };
  for (const auto& c : cases) {
    RawClient conn(port);
    ASSERT_TRUE(conn.connected());
    conn.send(c.request);
    const std::string r = conn.read_all();
    EXPECT_EQ(status_of(r), c.status) << c.request.substr(0, 60) << "\n" << r;
    EXPECT_NE(r.find(c.error), std::string::npos) << r;
  }
  // A small body is read and the request served; the next request on the connection is too.
  RawClient conn(port);
  conn.send(
      "GET /healthz HTTP/1.1\r\nContent-Length: 3\r\n\r\nabcGET /healthz HTTP/1.1\r\nConnection: "
      "close\r\n\r\n");
  const std::string r = conn.read_all();
  EXPECT_EQ(status_of(r), 200) << r;
  EXPECT_NE(r.find("HTTP/1.1 200", 10), std::string::npos) << "the pipelined request was not served:\n" << r;
  EXPECT_EQ(get_json("/v1/status")["http"]["oversize"], static_cast<int>(cases.size()));
}

TEST_F(NaneyedTest, PastTheConnectionCapIdleConnectionsMakeRoomAndSlowOnesGet503) {
  start("max_connections = 8\n" + looping_source(capture(12)));
  {
    // Eight idle keep-alive connections (each served once) are closed, oldest first, for newcomers.
    std::vector<std::unique_ptr<RawClient>> idle;
    for (int i = 0; i < 8; ++i) {
      idle.push_back(std::make_unique<RawClient>(port));
      idle.back()->send("GET /healthz HTTP/1.1\r\n\r\n");
      ASSERT_EQ(idle.back()->status(), 200) << i;
    }
    const auto j = get_json("/v1/status");
    EXPECT_EQ(j["http"]["idle_evicted"], 1);
    EXPECT_EQ(j["http"]["refused"], 0);
  }
  // The idle ones just closed count against the cap until the daemon has seen them go; a slow
  // connection arriving before that, its head not yet sent, was the newest with nothing to read and
  // was refused in the late one's place (1 run in 30 with both cores busy). So does the status
  // client's own keep-alive connection while a worker still holds it after its answer (not
  // evictable: 2 runs in 40 with both cores busy, 2026-12-07): that one is closed too, and the
  // daemon asked on connections that close, until it holds none but the asking one.
  client->stop();
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(15);
  for (;;) {
    RawClient probe(port);
    probe.send("GET /v1/status HTTP/1.1\r\nConnection: close\r\n\r\n");
    const std::string r = probe.read_all();  // to the daemon's close: it no longer holds this one
    const auto body = r.find("\r\n\r\n");
    if (status_of(r) == 200 && body != std::string::npos &&
        nlohmann::json::parse(r.substr(body + 4))["http"]["connections"].get<int>() <= 1) {
      break;
    }
    ASSERT_LT(std::chrono::steady_clock::now(), until) << "the closed connections stayed open:\n" << r;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  // Eight connections in the middle of their heads hold every place: the ninth is told at once.
  std::vector<std::unique_ptr<RawClient>> slow;
  for (int i = 0; i < 8; ++i) {
    slow.push_back(std::make_unique<RawClient>(port));
    slow.back()->send("GET /v1/status HTTP/1.1\r\n");
  }
  // No wait here: the gate counts a head's bytes as sent once they are in the socket, read or not
  // (with a fixed 500 ms sleep for its poll thread to read them, the test failed on a loaded host:
  // an unread connection was evicted as idle and the ninth served).
  RawClient late(port);
  late.send("GET /v1/status HTTP/1.1\r\n\r\n");
  // The refusal closes the connection, so this returns at once; the bound only says how long a loaded
  // host may keep the gate's poll thread (which runs niced) from getting to it.
  const std::string r = late.read_all(std::chrono::milliseconds(5000));
  EXPECT_EQ(status_of(r), 503) << r;
  EXPECT_NE(r.find("too_many_connections"), std::string::npos) << r;
  EXPECT_NE(r.find("Retry-After: 1"), std::string::npos) << r;
  slow.clear();
  // Once they are gone the daemon serves again.
  wait_status([](const nlohmann::json& s) { return s["http"]["refused"].get<int>() >= 1; });
}

TEST_F(NaneyedTest, QueryNumbersAreDecimalGivenOnceWithNoSpaceOrSign) {
  start(looping_source(capture(12)));
  wait_status([](const nlohmann::json& s) { return s["pairs"]["processed"] > 1; });
  for (const char* q :
       {"/v1/depth?max_age_ms=%2B500", "/v1/depth?max_age_ms=%20500", "/v1/depth?max_age_ms=500%20",
        "/v1/depth?max_age_ms=0x10", "/v1/depth?max_age_ms=500&max_age_ms=600", "/v1/depth?max_age_ms=",
        "/v1/depth?max_age_ms=1e3", "/v1/depth/at?u=0x10&v=3", "/v1/depth/at?u=%2B1&v=3",
        "/v1/depth/at?u=1&v=3&v=4", "/v1/depth/at?u=inf&v=3", "/v1/depth/at?u=%201&v=3",
        "/v1/frames/left.png?overlay=01%20", "/v1/status?x=1&x=2", "/v1/events?last_event_id=-1"}) {
    EXPECT_EQ(get_json(q, 400)["error"], "bad_parameter") << q;
  }
  // The plain forms still work (these captures show no board: 422 no_board is the pixel's answer).
  EXPECT_EQ(client->Get("/v1/depth?max_age_ms=60000")->status, 200);
  EXPECT_EQ(get_json("/v1/depth/at?u=125.5&v=-0.25", 422)["error"], "no_board");
  EXPECT_EQ(get_json("/v1/depth/at?u=1.25e2&v=110", 422)["error"], "no_board");
}

TEST_F(NaneyedTest, EventSlotsComeBackWhenClientsLeaveWhateverTheyAskedFor) {
  // Four clients asking for a result far in the future used to hold all four slots for good after
  // hanging up: every later /v1/events got 503 too_many_clients.
  start("[pipeline]\nsse_max_clients = 4\n" + looping_source(capture(12)));
  wait_status([](const nlohmann::json& s) { return s["pairs"]["processed"] > 1; });
  for (int round = 0; round < 2; ++round) {
    {
      std::vector<std::unique_ptr<RawClient>> gone;
      for (int i = 0; i < 4; ++i) {
        gone.push_back(std::make_unique<RawClient>(port));
        gone.back()->send("GET /v1/events?last_event_id=999999999999 HTTP/1.1\r\n\r\n");
        ASSERT_EQ(gone.back()->status(), 200) << i;
      }
      wait_status([](const nlohmann::json& s) { return s["events"]["clients"] == 4; });
    }
    wait_status([](const nlohmann::json& s) { return s["events"]["clients"] == 0; }, std::chrono::seconds(5));
  }
  // A future id starts the stream at the latest result (numbers restart with the daemon).
  RawClient fresh(port);
  fresh.send("GET /v1/events?last_event_id=999999999999 HTTP/1.1\r\n\r\n");
  const std::string r = fresh.read_all(std::chrono::milliseconds(1500));
  EXPECT_EQ(status_of(r), 200) << r.substr(0, 200);
  EXPECT_NE(r.find("event: result"), std::string::npos) << r.substr(0, 400);
}
