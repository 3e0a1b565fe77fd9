// The simulated lidars' intensity: what a UST-10LX reports with SCIP ME (its "reflectance",
// device units, undocumented in absolute terms), modelled so that surfaces differ as they
// would in a real room and the reading falls with range and incidence:
//   I = round(kMattWhiteAt0m * rho * |cos(incidence)| / (1 + r[m]))
// rho: the surface's diffuse reflectivity near 905 nm (surfaceReflectivity), incidence: the
// angle between the ray and the surface normal (Lambert's cosine law), r: the true range. A real
// UST compensates part of the 1/r^2 fall-off of the echo; 1/(1 + r) is the gentler fall-off of
// the SCIP emulator's matt wall (tools/emulate/scip_device.hpp: 20000 / (1 + r), rho = 1 at
// normal incidence). No randomness: the intensity follows from the geometry alone, so the
// simulator's random streams and its ranges are what they were without it.
// Rig B's simulated YDLIDAR X4 (sim/mobile.hpp) reports none, as a real X4: its packets
// carry distances only.
#pragma once

#include <string>

namespace sweepmap {

constexpr double kMattWhiteAt0m = 20000.0;

// Diffuse reflectivity (0..1) of a scene surface by its box name (sim/scene.hpp): walls and
// the door lintel 0.7 (white paint), ceiling 0.8, floor 0.3 (carpet), door leaf 0.45 (wood),
// table and cabinet 0.1 (dark: the ones sim/artefacts.hpp drops), stand post 0.3, target board
// 0.9 (white board), the target window's back 0.2; anything else 0.5.
double surfaceReflectivity(const std::string& box_name);
// Artefacts and the plate (sim/artefacts.hpp, sim/lidar.hpp).
constexpr double kPlateReflectivity = 0.6;  // matt aluminium
constexpr double kWhiteboardReflectivity = 0.85;
constexpr double kPersonReflectivity = 0.4;  // clothing

// The formula above; 0 for a range <= 0 (no return).
float simulatedIntensity(double reflectivity, double cos_incidence, double range_m);

}  // namespace sweepmap
