// A scene file (`--scene`, geometry::LoadScene) and the shape arguments of
// `flowplan plan` (`--sphere/--box/--cylinder/--capsule x,y,...`, parsed by
// ParseNumbers and added by geometry::AddObstacle). The first byte picks: even,
// the rest is a scene file; odd, each line of the rest is "KIND VALUES" with
// KIND one of spheres, boxes, cylinders, capsules. The scene is 2-D when the
// byte is 1 or 2 mod 4, else 3-D.

#include <sstream>

#include "core/format.h"
#include "fuzz/fuzz_input.h"
#include "geometry/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  try {
    const int W = data[0] % 4 == 1 || data[0] % 4 == 2 ? 2 : 3;
    if (data[0] % 2 == 0) {
      const flowplan::geometry::Scene scene =
          flowplan::geometry::LoadScene(flowplan::fuzz::AsFile(data + 1, size - 1, ".yaml"));
      scene.Validate(W, "scene");
    } else {
      flowplan::geometry::Scene scene;
      std::istringstream lines(std::string(reinterpret_cast<const char*>(data + 1), size - 1));
      for (std::string line; std::getline(lines, line);) {
        const size_t space = line.find(' ');
        const std::string kind = line.substr(0, space);
        // The command line adds only these kinds (AddObstacle takes no other: its caller's bug, not input).
        if (kind != "spheres" && kind != "boxes" && kind != "cylinders" && kind != "capsules") continue;
        const std::string values = space == std::string::npos ? "" : line.substr(space + 1);
        flowplan::geometry::AddObstacle(scene, kind, flowplan::ParseNumbers(values, "--" + kind),
                                        W, "--" + kind + " \"" + values + "\"");
      }
      scene.Validate(W, "command line");
    }
  } catch (const flowplan::Error& error) {
    flowplan::fuzz::ExpectOneLine(error);
  }
  return 0;
}
