// MoveIt scene and request files (`flowplan scenes import`): the first byte
// picks a scene (even) or a request (odd), read with the Franka's joint names;
// a request is read with an empty scene file for its start.

#include "fuzz/fuzz_input.h"
#include "problems/moveit_import.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  flowplan::problems::MoveItImportOptions options;
  options.joint_names = flowplan::problems::FrankaJointNames();
  options.held_names = {"panda_finger_joint1", "panda_finger_joint2"};
  try {
    if (data[0] % 2 == 0) {
      flowplan::problems::ReadMoveItScene(flowplan::fuzz::AsFile(data + 1, size - 1, "_scene.yaml"), options);
    } else {
      const uint8_t empty[] = {'{', '}'};
      const std::string scene = flowplan::fuzz::AsFile(empty, sizeof(empty), "_empty.yaml");
      std::vector<double> start, goal;
      flowplan::problems::ReadMoveItRequest(flowplan::fuzz::AsFile(data + 1, size - 1, "_request.yaml"), scene,
                                            options, start, goal);
    }
  } catch (const flowplan::Error& error) {
    flowplan::fuzz::ExpectOneLine(error);
  }
  return 0;
}
