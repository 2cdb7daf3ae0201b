// A URDF as `flowplan robot import` reads it (robotfiles::ImportUrdf), with a
// cheap sphere fit, then the robot folder's YAML it would write read back.

#include "fuzz/fuzz_input.h"
#include "robotfiles/urdf_import.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = flowplan::fuzz::AsFile(data, size, ".urdf");
  try {
    flowplan::robotfiles::ImportOptions options;
    options.overshoot = 0.2;  // a coarse fit on a coarse surface: a few spheres a link, quickly under ASan
    options.surface_spacing = 0.05;
    options.pair_samples = 20;
    const flowplan::robotfiles::ImportResult result = flowplan::robotfiles::ImportUrdf(path, options);
    result.file.Description("robot.yaml");
  } catch (const flowplan::Error& error) {
    flowplan::fuzz::ExpectOneLine(error);
  }
  return 0;
}
