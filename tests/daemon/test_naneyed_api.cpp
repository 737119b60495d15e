// The real naneyed on a freshly written capture, every endpoint queried and checked against the
// capture's truth (pair timestamps, offset, frame rate, pixels).
#include <opencv2/imgcodecs.hpp>

#include "naneyed_fixture.hpp"

using namespace naneye::daemon::test;

TEST_F(NaneyedTest, ServesEveryEndpointWhileStreamingARealTimeReplay) {
  const auto file = capture(40);
  start("[source]\nuri = \"file://" + file.string() + "?speed=realtime&loop=1\"\n");

  // Ready once results stream in.
  wait_status(
      [](const nlohmann::json& s) { return s["state"] == "streaming" && s["pairs"]["processed"] > 10; });
  auto ready = client->Get("/readyz");
  ASSERT_TRUE(ready);
  EXPECT_EQ(ready->status, 200) << ready->body;
  EXPECT_EQ(get_json("/healthz")["status"], "alive");

  const auto st = get_json("/v1/status");
  EXPECT_EQ(st["source"]["kind"], "file");
  EXPECT_EQ(st["source"]["live"], true);
  EXPECT_EQ(st["source"]["fallback"], false);
  EXPECT_EQ(st["version"], "0.1.0");
  EXPECT_NEAR(st["fps"]["left"].get<double>(), truth.fps(), 0.5);
  EXPECT_NEAR(st["fps"]["right"].get<double>(), truth.fps(), 0.5);
  EXPECT_NEAR(st["offset_ms"].get<double>(), truth.offset_ns() * 1e-6, 1e-3);
  for (const char* c : {"bytes", "records", "sync_losses", "seq_gaps", "cut_records", "reference_failures",
                        "reference_unchecked", "unpaired", "pairs", "pairs_dropped", "reconnects",
                        "transfer_errors", "stalls"}) {
    EXPECT_TRUE(st["counters"].contains(c)) << c;
  }
  EXPECT_EQ(st["counters"]["sync_losses"], 0);
  EXPECT_EQ(st["counters"]["reference_failures"], 0);
  EXPECT_EQ(st["counters"]["reference_unchecked"], 0);  // a file's records carry the reference pixels
  EXPECT_GE(st["counters"]["records"].get<int>(), 2 * st["counters"]["pairs"].get<int>());
  EXPECT_GE(
      st["counters"]["bytes"].get<std::int64_t>(),
      st["counters"]["records"].get<std::int64_t>() * static_cast<std::int64_t>(naneye::driver::kRecordSize));
  EXPECT_GT(st["recon_ms"]["samples"].get<int>(), 0);
  EXPECT_LE(st["recon_ms"]["p50"].get<double>(), st["recon_ms"]["p99"].get<double>());
  EXPECT_GT(st["uptime_s"].get<double>(), 0.0);
  EXPECT_LT(st["last_result_age_ms"].get<double>(), 1000.0);

  // The latest result: its timestamps are the capture's.
  const auto d = get_json("/v1/depth");
  EXPECT_EQ(d["t_right_ns"].get<std::int64_t>() - d["t_left_ns"].get<std::int64_t>(), truth.offset_ns());
  EXPECT_GE(d["age_ms"].get<double>(), 0.0);
  EXPECT_EQ(d["board_found"], false);  // no corner detector wired in yet, and none is invented
  EXPECT_EQ(d["reference"], nlohmann::json({{"left", "passed"}, {"right", "passed"}}));
  EXPECT_TRUE(d["board"].is_null());
  EXPECT_TRUE(d["metrics"].is_null());
  EXPECT_EQ(get_json("/v1/depth?max_age_ms=60000")["t_right_ns"].is_number(), true);
  EXPECT_EQ(get_json("/v1/depth?max_age_ms=0", 503)["error"], "stale_result");

  // Depth at a pixel needs a board; bad pixels are refused first.
  EXPECT_EQ(get_json("/v1/depth/at?u=125&v=110", 422)["error"], "no_board");
  EXPECT_EQ(get_json("/v1/depth/at?u=300&v=10", 422)["error"], "outside_image");
  EXPECT_EQ(get_json("/v1/depth/at?u=abc&v=10", 400)["error"], "bad_parameter");
  EXPECT_EQ(get_json("/v1/depth/at?u=10", 400)["error"], "bad_parameter");

  const auto pts = get_json("/v1/points");
  EXPECT_TRUE(pts["points"].is_array());
  EXPECT_EQ(pts["points"].size(), 0u);
  auto ply = client->Get("/v1/points.ply");
  ASSERT_TRUE(ply);
  EXPECT_EQ(ply->status, 200);
  EXPECT_EQ(ply->body.rfind("ply\nformat ascii 1.0\n", 0), 0u);
  EXPECT_NE(
      ply->body.find("element vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n"),
      std::string::npos);
  EXPECT_EQ(get_json("/v1/points.ply?which=nonsense", 400)["error"], "bad_parameter");

  // Frames: the served PNG is the capture's frame, 10 -> 8 bits.
  for (int sensor = 0; sensor < 2; ++sensor) {
    auto png = client->Get(sensor == 0 ? "/v1/frames/left.png" : "/v1/frames/right.png");
    ASSERT_TRUE(png);
    ASSERT_EQ(png->status, 200);
    EXPECT_EQ(png->get_header_value("Content-Type"), "image/png");
    const int k = std::stoi(png->get_header_value("X-Naneye-Pair")) % truth.pairs;
    const cv::Mat img =
        cv::imdecode(std::vector<uchar>(png->body.begin(), png->body.end()), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(img.type(), CV_8UC1);
    ASSERT_EQ(img.rows, 250);
    int wrong = 0;
    for (int r = 0; r < 250; ++r)
      for (int c = 0; c < 250; ++c) wrong += img.at<uchar>(r, c) != (pixel(k, sensor, r, c) >> 2);
    EXPECT_EQ(wrong, 0) << "sensor " << sensor << " pair " << k;
  }
  auto overlay = client->Get("/v1/frames/left.png?overlay=1");
  ASSERT_TRUE(overlay);
  EXPECT_EQ(cv::imdecode(std::vector<uchar>(overlay->body.begin(), overlay->body.end()), cv::IMREAD_UNCHANGED)
                .type(),
            CV_8UC3);
  EXPECT_EQ(get_json("/v1/frames/left.png?overlay=2", 400)["error"], "bad_parameter");

  // Prometheus text.
  auto m = client->Get("/metrics");
  ASSERT_TRUE(m);
  EXPECT_EQ(m->status, 200);
  EXPECT_NE(m->get_header_value("Content-Type").find("text/plain; version=0.0.4"), std::string::npos);
  for (const char* needle :
       {"# HELP naneye_pairs_processed_total ", "# TYPE naneye_pairs_processed_total counter\n",
        "# TYPE naneye_source_pairs_dropped_total counter\n",
        "# TYPE naneye_recon_duration_seconds histogram\n",
        "naneye_recon_duration_seconds_bucket{le=\"+Inf\"} ", "naneye_recon_duration_seconds_count ",
        "naneye_state{state=\"streaming\"} 1\n", "naneye_build_info{version=\"0.1.0\"} 1\n"}) {
    EXPECT_NE(m->body.find(needle), std::string::npos) << needle;
  }
  const auto at = m->body.find("\nnaneye_pairs_processed_total ");
  ASSERT_NE(at, std::string::npos);
  EXPECT_GT(std::stoll(m->body.substr(at + 30)), 10);

  // Errors.
  EXPECT_EQ(get_json("/v1/nothing-here", 404)["error"], "not_found");
  EXPECT_EQ(get_json("/v1/status?verbose=1", 400)["error"], "bad_parameter");
  EXPECT_EQ(get_json("/v1/depth?max_age_ms=-3", 400)["error"], "bad_parameter");
  EXPECT_EQ(get_json("/v1/events?last_event_id=x", 400)["error"], "bad_parameter");

  const auto [code, took] = daemon->stop(SIGTERM);
  EXPECT_EQ(code, 0) << daemon->log();
}

TEST_F(NaneyedTest, AnswersBeforeTheFirstResultWith503) {
  // A source that does not exist yet: the service runs, serves HTTP and waits for it.
  const auto file = dir.path / "later.raw";
  start("[source]\nuri = \"file://" + file.string() + "?speed=realtime&loop=1\"\n");
  const auto st = wait_status([](const nlohmann::json& s) { return s["state"] == "waiting_for_device"; });
  EXPECT_EQ(get_json("/v1/depth", 503)["error"], "no_result");
  EXPECT_EQ(get_json("/v1/points", 503)["error"], "no_result");
  EXPECT_EQ(get_json("/v1/frames/left.png", 503)["error"], "no_frame");
  EXPECT_EQ(get_json("/readyz", 503)["error"], "not_ready");
  EXPECT_EQ(get_json("/healthz")["status"], "alive");
  // The device comes (back): streaming resumes without a restart.
  const auto tmp = dir.path / "writing.raw";
  truth = write_capture(tmp, 20);
  std::filesystem::rename(tmp, file);
  wait_status(
      [](const nlohmann::json& s) { return s["state"] == "streaming" && s["pairs"]["processed"] > 3; });
  EXPECT_GE(get_json("/v1/status")["source"]["opens"].get<int>(), 1);
  // One read: two reads may see two different pairs while the replay runs.
  const auto depth = get_json("/v1/depth");
  EXPECT_EQ(depth["t_right_ns"].get<std::int64_t>() - depth["t_left_ns"].get<std::int64_t>(),
            truth.offset_ns());
  EXPECT_EQ(daemon->stop(SIGTERM).first, 0);
}

TEST_F(NaneyedTest, AutoFallsBackToTheSampleCaptureAndSaysSo) {
  const auto file = capture(20, "sample.raw");
  start("[source]\nuri = \"auto\"\nsample_capture = \"" + file.string() + "\"\n");
  const auto st = wait_status([](const nlohmann::json& s) { return s["pairs"]["processed"] > 0; });
  EXPECT_EQ(st["source"]["requested"], "auto");
  EXPECT_EQ(st["source"]["fallback"], true);
  EXPECT_NE(st["source"]["reason"].get<std::string>().find("no NanEye readout board attached"),
            std::string::npos);
  EXPECT_NE(st["source"]["uri"].get<std::string>().find("loop=1"), std::string::npos);
  EXPECT_NE(daemon->log().find("replaying the bundled sample capture"), std::string::npos);
  EXPECT_EQ(daemon->stop(SIGINT).first, 0);
}
