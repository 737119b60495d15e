#pragma once
// The paper's own figures (Dias et al., ICDSC 2016, Sec. 4), as printed: P and D in mm, R in px. The
// study prints them beside ours. Its five planes are five of its 19 Dataset 3 images.
#include <array>

namespace naneye::tools::study::paper {

struct PDR {
  double P, D, R;
};
using FivePlanes = std::array<PDR, 5>;

// Table "Results for the baseline approach".
inline constexpr FivePlanes kBaseline{{{2.718, 1.267, 0.077},
                                       {3.497, 3.2350, 0.119},
                                       {2.805, 3.280, 0.110},
                                       {1.777, 0.1460, 0.313},
                                       {5.702, 5.7960, 0.180}}};
// Table "Results for the division model with triangulation".
inline constexpr FivePlanes kDivisionTriangulation{{{5.806, 2.013, 1.512},
                                                    {5.158, 4.128, 1.215},
                                                    {3.005, 3.494, 0.405},
                                                    {2.482, 0.489, 1.171},
                                                    {7.629, 14.041, 2.117}}};
// Table "Results for the division model with plane-sweep".
inline constexpr FivePlanes kDivisionSweep{{{5.802, 2.015, 1.512},
                                            {5.166, 4.117, 1.215},
                                            {3.002, 3.481, 0.405},
                                            {2.479, 0.483, 1.171},
                                            {7.632, 14.022, 2.117}}};
// Table "division model with normalized coordinates, un-distortion and then triangulation".
inline constexpr FivePlanes kNormalizedTriangulation{{{6.942, 0.8080, 2.716},
                                                      {4.206, 3.7432, 0.854},
                                                      {4.864, 4.5740, 1.656},
                                                      {1.640, 0.1930, 0.353},
                                                      {833.587, 1482, 17.741}}};
// Table "division model with normalized coordinates and the triangulating with distorted coordinates".
inline constexpr FivePlanes kNormalizedDirect{{{5.4793, 2.015, 2.720},
                                               {4.070, 4.1170, 0.908},
                                               {4.433, 3.4810, 1.710},
                                               {1.594, 0.9110, 0.416},
                                               {26.554, 42.788, 18.102}}};
// Table "Comparison of distortion models" (six synthetic points).
inline constexpr PDR kSixBaseline{0.256, 0.6280, 0.863};
inline constexpr PDR kSixDivisionTriangulation{0.008, 9.291, 57.556};
inline constexpr PDR kSixDivisionSweep{0.006, 9.283, 59.374};

// Cross-validation (calibration on 10 images, evaluation on the other 9; three tests, planes A, B, C):
// Tables "Results for the baseline model", "division model with triangulation", "... normalized
// coordinates and triangulation". Row t * 3 + k is Test t + 1, plane A/B/C.
using NinePlanes = std::array<PDR, 9>;
inline constexpr NinePlanes kCrossBaseline{{{2.070, 1.172, 0.114},
                                            {3.046, 3.000, 0.114},
                                            {2.323, 1.209, 0.417},
                                            {2.182, 2.401, 0.172},
                                            {2.857, 5.011, 0.245},
                                            {2.760, 1.380, 0.455},
                                            {2.818, 2.216, 0.059},
                                            {3.611, 3.888, 0.088},
                                            {3.112, 3.536, 0.257}}};
inline constexpr NinePlanes kCrossDivision{{{2.740, 1.489, 1.792},
                                            {2.682, 3.063, 0.872},
                                            {2.004, 1.198, 1.240},
                                            {3.052, 3.503, 1.895},
                                            {4.547, 7.225, 2.356},
                                            {2.747, 2.738, 1.227},
                                            {3.273, 2.842, 1.495},
                                            {2.986, 4.301, 0.743},
                                            {2.793, 2.728, 1.593}}};
inline constexpr NinePlanes kCrossNormalized{{{2.578, 1.862, 4.497},
                                              {2.365, 2.946, 0.431},
                                              {2.077, 1.283, 0.531},
                                              {4.521, 2.899, 2.474},
                                              {3.928, 38.602, 9.103},
                                              {2.563, 2.757, 0.602},
                                              {2.396, 3.646, 2.961},
                                              {3.690, 3.892, 0.705},
                                              {3.269, 4.054, 1.897}}};

}  // namespace naneye::tools::study::paper
