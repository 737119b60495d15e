// /v1/events: Server-Sent Events, one "result" event per processed pair. A client's queue is the
// window of results the pipeline still holds ahead of its cursor (pipeline.history): the pipeline
// never waits for a client, and a client that falls further behind than that is dropped.
#include <thread>

#include "http_internal.hpp"
#include "naneye/base/clock.hpp"

namespace naneye::daemon::http {
namespace {

struct Stream {
  HttpContext* ctx;
  std::uint64_t cursor;  // next result number to send
  std::int64_t last_write_ns;
};

// With nothing to send, a comment line this often. A client that went away is only seen when a
// write fails (a closed peer's socket stays writable): without it a stream waiting for a result
// that never comes (a future last_event_id, a stalled source) held its slot and thread for good.
// 1 s: the second write after the peer's close fails (the first draws its RST), so a slot is free
// within ~2 s; 13 bytes a second is nothing next to a result event (~15 kB).
constexpr std::int64_t kHeartbeatNs = 1'000'000'000;

}  // namespace

void add_event_routes(httplib::Server& svr, HttpContext& ctx) {
  svr.Get("/v1/events", [&ctx](const httplib::Request& req, httplib::Response& res) {
    if (!only_params(req, res, {"last_event_id"})) return;
    // EventSource resends the id of the last event it got as Last-Event-ID when it reconnects;
    // the query parameter does the same for a first connection.
    std::optional<std::int64_t> last;
    if (!int_param(req, res, "last_event_id", 0, INT64_MAX, last)) return;
    if (!last && req.has_header("Last-Event-ID")) {
      const std::string h = req.get_header_value("Last-Event-ID");
      last = strict_int(h, 0, INT64_MAX);
      if (!last || req.get_header_value_count("Last-Event-ID") > 1) {
        return send_error(res, 400, "bad_parameter",
                          "Last-Event-ID must be one result number, got \"" + h + "\"");
      }
    }
    if (ctx.sse_clients.fetch_add(1) >= ctx.settings.sse_max_clients) {
      ctx.sse_clients.fetch_sub(1);
      return send_error(res, 503, "too_many_clients",
                        "at most " + std::to_string(ctx.settings.sse_max_clients) + " event streams at once");
    }
    auto stream = std::make_shared<Stream>();
    stream->ctx = &ctx;
    stream->last_write_ns = base::monotonic_ns();
    // Without a resume point, start with the latest result so the client has one at once. An id
    // beyond the latest is from an earlier run of the daemon (numbers restart at 1): the same.
    const auto latest = ctx.pipeline->results().latest_seq();
    const bool resumes = last && latest && static_cast<std::uint64_t>(*last) <= *latest;
    stream->cursor = resumes ? static_cast<std::uint64_t>(*last) + 1 : latest.value_or(1);
    res.set_header("Cache-Control", "no-cache");
    res.set_header("X-Accel-Buffering", "no");
    res.set_chunked_content_provider(
        "text/event-stream",
        [stream](std::size_t, httplib::DataSink& sink) {
          HttpContext& c = *stream->ctx;
          const auto& results = c.pipeline->results();
          if (c.stopping.load()) {
            sink.done();
            return true;
          }
          const auto latest = results.latest_seq();
          if (!latest || stream->cursor > *latest) {
            if (base::monotonic_ns() - stream->last_write_ns >= kHeartbeatNs) {
              stream->last_write_ns = base::monotonic_ns();
              static constexpr char kBeat[] = ": keep-alive\n\n";
              return sink.write(kBeat, sizeof kBeat - 1);
            }
            // Nothing new: poll (the pipeline does not signal readers, so that it never waits).
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
            return true;
          }
          std::string event;
          const bool held = results.read_seq(stream->cursor, [&](const Published& p) {
            const double age = static_cast<double>(base::monotonic_ns() - p.published_ns) * 1e-6;
            event = "id: " + std::to_string(p.seq) + "\nevent: result\ndata: ";
            append_with_age(event, age, *result_json_text(c, p));
            event += "\n\n";
          });
          if (!held) {
            c.sse_dropped.fetch_add(1);
            const nlohmann::json err{{"error", "slow_client"},
                                     {"detail", "result " + std::to_string(stream->cursor) +
                                                    " is no longer held; the client fell more than " +
                                                    std::to_string(c.settings.history) + " results behind"}};
            const std::string msg = "event: dropped\ndata: " + err.dump() + "\n\n";
            sink.write(msg.data(), msg.size());
            sink.done();
            return true;
          }
          ++stream->cursor;
          stream->last_write_ns = base::monotonic_ns();
          c.sse_events.fetch_add(1, std::memory_order_relaxed);
          return sink.write(event.data(), event.size());
        },
        [stream](bool) { stream->ctx->sse_clients.fetch_sub(1); });
  });
}

}  // namespace naneye::daemon::http
