// naneyed's HTTP serving itself: keep-alive connections, the request counters of /metrics, and the
// one serialization of a result shared by /v1/depth and /v1/events.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include "naneyed_fixture.hpp"
#include "raw_client.hpp"

using namespace naneye::daemon::test;

namespace {

double metric(httplib::Client& c, const std::string& name) {
  const auto m = c.Get("/metrics");
  if (!m) return -1;
  const auto at = m->body.find("\n" + name + " ");
  return at == std::string::npos ? -1 : std::stod(m->body.substr(at + name.size() + 2));
}

// The body without its "age_ms" member, which /v1/depth and /v1/events put first.
std::string without_age(const std::string& json) {
  EXPECT_EQ(json.rfind("{\"age_ms\":", 0), 0u) << json.substr(0, 40);
  const auto comma = json.find(',');
  return comma == std::string::npos ? json : "{" + json.substr(comma + 1);
}

}  // namespace

TEST_F(NaneyedTest, AKeepAliveConnectionServesAHundredRequestsAndEachIsCounted) {
  const auto file = capture(40);
  start("[source]\nuri = \"file://" + file.string() + "?speed=realtime&loop=1\"\n");
  wait_status([](const nlohmann::json& s) { return s["pairs"]["processed"] > 3; });
  const double served0 = metric(*client, "naneye_depth_served_total");
  const double requests0 = metric(*client, "naneye_http_requests_total");
  ASSERT_GE(served0, 0);
  ASSERT_GE(requests0, 0);

  // httplib's default would close the connection after 5 requests; naneyed keeps it for 100, then
  // closes it so that a waiting connection gets the thread.
  RawClient conn(port);
  ASSERT_TRUE(conn.connected());
  for (int k = 1; k <= 100; ++k) {
    const auto r = conn.get("/v1/depth");
    ASSERT_TRUE(r) << "connection closed by the server before request " << k;
    ASSERT_EQ(r->status, 200) << r->body;
    const auto j = nlohmann::json::parse(r->body);
    EXPECT_GE(j["age_ms"].get<double>(), 0.0);
    EXPECT_EQ(j["board_found"], false);
    EXPECT_EQ(r->head.find("Connection: close") != std::string::npos, k == 100) << "request " << k;
  }
  EXPECT_TRUE(conn.closed_by_server());

  // Two 400s and a 404 count as requests, not as served results.
  EXPECT_EQ(get_json("/v1/depth?max_age_ms=x", 400)["error"], "bad_parameter");
  EXPECT_EQ(get_json("/v1/depth?nonsense=1", 400)["error"], "bad_parameter");
  EXPECT_EQ(get_json("/v1/nothing", 404)["error"], "not_found");
  EXPECT_EQ(metric(*client, "naneye_depth_served_total") - served0, 100);
  // Counted before their handler runs: the /metrics that read requests0 counted itself before, the
  // two /metrics reads since (served, then this one) inside: 100 + 3 + 2.
  EXPECT_EQ(metric(*client, "naneye_http_requests_total") - requests0, 105);
}

TEST_F(NaneyedTest, DepthAndEventsServeTheSameTextOfAResult) {
  const int n = 12;
  const auto file = capture(n);
  serve_replay(file, n);

  const auto a = client->Get("/v1/depth");
  const auto b = client->Get("/v1/depth");
  ASSERT_TRUE(a && b);
  ASSERT_EQ(a->status, 200);
  const auto pair = nlohmann::json::parse(a->body)["pair"].get<int>();
  EXPECT_EQ(pair, n - 1);
  EXPECT_EQ(without_age(a->body), without_age(b->body));

  // The event for the same result (the latest, id n) and an older one (id n - 1).
  std::vector<std::string> data;
  std::string buffer;
  client->Get(
      ("/v1/events?last_event_id=" + std::to_string(n - 2)).c_str(), [&](const char* d, std::size_t len) {
        buffer.append(d, len);
        for (std::size_t end; (end = buffer.find("\n\n")) != std::string::npos; buffer.erase(0, end + 2)) {
          const auto at = buffer.find("data: ");
          if (at < end) data.push_back(buffer.substr(at + 6, end - at - 6));
        }
        return data.size() < 2;
      });
  ASSERT_EQ(data.size(), 2u);
  EXPECT_EQ(nlohmann::json::parse(data[0])["pair"], n - 2);
  EXPECT_EQ(without_age(data[1]), without_age(a->body));
  // And the text is exactly nlohmann's serialization of the same object.
  auto parsed = nlohmann::json::parse(a->body);
  parsed.erase("age_ms");
  EXPECT_EQ(without_age(a->body), parsed.dump());
}

TEST_F(NaneyedTest, BodiesAreNeverCompressedEvenWhenTheClientAcceptsIt) {
  // httplib would compress each of them per request (brotli quality 11: milliseconds of CPU for one
  // /v1/depth); naneyed sends them as they are, which any client accepts.
  const auto file = capture(12);
  serve_replay(file, 12);
  RawClient conn(port);
  ASSERT_TRUE(conn.connected());
  for (const char* path : {"/v1/depth", "/v1/status", "/metrics", "/v1/points", "/v1/nothing"}) {
    for (const char* enc : {"br", "gzip, deflate, br", "gzip"}) {
      const auto r = conn.get(path, std::string("Accept-Encoding: ") + enc + "\r\n");
      ASSERT_TRUE(r) << path;
      EXPECT_EQ(r->head.find("Content-Encoding"), std::string::npos) << path << " " << enc << "\n" << r->head;
      if (std::string(path) == "/metrics") {
        EXPECT_EQ(r->body.rfind("# HELP ", 0), 0u);
      } else {
        const auto j = nlohmann::json::parse(r->body);
        EXPECT_EQ(j.contains("error"), std::string(path) == "/v1/nothing") << path;
      }
    }
  }
  const auto d = nlohmann::json::parse(conn.get("/v1/depth", "Accept-Encoding: br\r\n")->body);
  EXPECT_EQ(d["pair"], 11);
}

TEST_F(NaneyedTest, InvalidUtf8FromAClientGets400AndTheDaemonLives) {
  // "/%ff" used to terminate naneyed: its 404 body put the decoded path into JSON, nlohmann threw on
  // the invalid UTF-8, and httplib's error handler runs outside its try block.
  const auto file = capture(12);
  start("[source]\nuri = \"file://" + file.string() + "?speed=realtime&loop=1\"\n");
  wait_status([](const nlohmann::json& s) { return s["pairs"]["processed"] > 1; });
  RawClient conn(port);
  ASSERT_TRUE(conn.connected());
  struct Case {
    const char* path;
    const char* header;
  };
  for (const Case c :
       {Case{"/%ff", ""}, Case{"/v1/nothing%fe%ff", ""}, Case{"/v1/depth?max_age_ms=%ff", ""},
        Case{"/v1/depth?%ff=1", ""}, Case{"/%c0%af", ""} /* overlong "/" */,
        Case{"/%ed%a0%80", ""} /* a UTF-16 surrogate */, Case{"/%f4%90%80%80", ""} /* > U+10FFFF */,
        Case{"/v1/status", "X-Probe: \xff\xfe\r\n"}}) {
    const auto r = conn.get(c.path, c.header);
    ASSERT_TRUE(r) << c.path << ": the connection died (daemon gone?)\n" << daemon->log();
    EXPECT_EQ(r->status, 400) << c.path << " " << r->body;
    EXPECT_EQ(nlohmann::json::parse(r->body)["error"], "bad_encoding") << c.path;
  }
  // Well-formed UTF-8 is still an ordinary path: 404 naming it.
  const auto ok = conn.get("/caf%C3%A9");
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->status, 404);
  EXPECT_NE(nlohmann::json::parse(ok->body)["detail"].get<std::string>().find("/caf\xC3\xA9"),
            std::string::npos);
  EXPECT_EQ(get_json("/v1/status")["state"].is_string(), true);
}

TEST_F(NaneyedTest, AResumePointFromAnEarlierRunStartsAtTheLatestResult) {
  // An EventSource that reconnects to a restarted naneyed sends the last id of the previous run;
  // ids restart at 1, so it used to wait (silently) until this run caught up with it.
  const int n = 12;
  const auto file = capture(n);
  serve_replay(file, n);
  for (const std::string how : {"query", "header"}) {
    std::string buffer, first_id;
    httplib::Headers headers;
    std::string path = "/v1/events";
    if (how == "query")
      path += "?last_event_id=100000";
    else
      headers.emplace("Last-Event-ID", "100000");
    client->Get(path.c_str(), headers, [&](const char* d, std::size_t len) {
      buffer.append(d, len);
      const auto at = buffer.find("id: ");
      const auto end = buffer.find('\n', at);
      if (at == std::string::npos || end == std::string::npos) return true;
      first_id = buffer.substr(at + 4, end - at - 4);
      return false;
    });
    EXPECT_EQ(first_id, std::to_string(n)) << how << ": " << buffer.substr(0, 200);
  }
}
