// A robot folder's robot.yaml (robotfiles::LoadRobotFile), then the robot as
// planned (its description with the collision body applied).

#include "fuzz/fuzz_input.h"
#include "robotfiles/robot_folder.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = flowplan::fuzz::AsFile(data, size, ".yaml");
  try {
    const flowplan::robotfiles::RobotFile file = flowplan::robotfiles::LoadRobotFile(path);
    file.Description(path);
  } catch (const flowplan::Error& error) {
    flowplan::fuzz::ExpectOneLine(error);
  }
  return 0;
}
