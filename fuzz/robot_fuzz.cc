// A robot description (what checkpoints, exported planners and plan files
// carry as YAML: kinematics::RobotFromYaml), then its collision body
// (collision::BodyModel), the form the planners and the checker use.

#include "collision/body_model.h"
#include "fuzz/fuzz_input.h"
#include "kinematics/robot_description.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    const flowplan::kinematics::RobotDescription robot = flowplan::kinematics::RobotFromYaml(
        std::string(reinterpret_cast<const char*>(data), size), "robot.yaml");
    const flowplan::collision::BodyModel body(robot, "robot.yaml");
    flowplan::kinematics::RobotToYaml(robot);
  } catch (const flowplan::Error& error) {
    flowplan::fuzz::ExpectOneLine(error);
  }
  return 0;
}
