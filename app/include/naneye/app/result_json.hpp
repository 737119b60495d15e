#pragma once
// PairResult <-> JSON: the object of issue #5 that `naneye recon --json` prints and naneyed serves at
// /v1/depth and /v1/events. One serializer for both so they cannot drift apart.
#include <nlohmann/json.hpp>

#include "naneye/app/scene_result.hpp"
#include "naneye/recon/pair/result.hpp"

namespace naneye::app {

// {"pair", "t_left_ns", "t_right_ns", "board_found", "points": [...], "board": {...}|null,
//  "metrics": {...}|null}; invalid points carry null coordinates.
nlohmann::json result_to_json(const recon::PairResult& r);
// The same with the pair's "scene" object (scene_json.hpp) when the scene path ran on it.
nlohmann::json result_to_json(const recon::PairResult& r, const SceneResult& scene);

// The inverse (for clients and tests); throws nlohmann::json::exception on a malformed object and
// std::invalid_argument when it holds more than recon::kMaxCorners points.
recon::PairResult result_from_json(const nlohmann::json& j);

}  // namespace naneye::app
