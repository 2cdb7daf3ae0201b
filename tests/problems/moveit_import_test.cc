// Importing MoveIt scenes and requests, checked against MuJoCo (the imported
// shapes placed as geoms, its kinematics for the TCP) and Eigen's quaternions.

#include "problems/moveit_import.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "sim/franka_execution.h"
#include "sim/franka_model.h"
#include "sim/mujoco_util.h"
#include "tests/support/scratch_dir.h"

namespace flowplan::problems {
namespace {

using ::testing::HasSubstr;

const collision::BodyModel& Franka() {
  static const collision::BodyModel arm(sim::LoadFrankaModel().description());
  return arm;
}

std::string Write(const std::string& name, const std::string& text) {
  const std::string path = (flowplan::testing::ScratchDir() / name).string();
  std::ofstream(path) << text;
  return path;
}

MoveItImportOptions Options() {
  MoveItImportOptions options;
  options.joint_names = FrankaJointNames();
  options.held_names = {"panda_finger_joint1", "panda_finger_joint2"};
  return options;
}

// A ready posture, and the same turned at the base and bent at the elbow.
const std::vector<double> kStart = {0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8};
const std::vector<double> kGoal = {0.6, 0.1, 0.0, -2.0, 0.0, 2.1, 0.8};

/// A request with the joints in a shuffled order, the fingers among them.
std::string Request(const std::vector<double>& start, const std::vector<double>& goal) {
  std::string text = "start_state:\n  joint_state:\n    name: [panda_finger_joint1";
  for (int j : {6, 0, 3, 1, 5, 2, 4}) text += ", panda_joint" + std::to_string(j + 1);
  text += "]\n    position: [0.04";
  for (int j : {6, 0, 3, 1, 5, 2, 4}) text += ", " + std::to_string(start[j]);
  text += "]\ngroup_name: panda_arm\ngoal_constraints:\n  - name: ''\n    joint_constraints:\n";
  for (int j : {3, 1, 0, 2, 6, 5, 4}) {
    text += "      - {joint_name: panda_joint" + std::to_string(j + 1) + ", position: " + std::to_string(goal[j]) +
            ", tolerance_above: 0.001, tolerance_below: 0.001, weight: 1}\n";
  }
  return text;
}

// A box turned 45° about z (list form), a cylinder tilted about x (mapping
// form, integer type), a sphere, all in the base frame.
const char* kScene = R"(name: test
world:
  collision_objects:
    - header: {frame_id: panda_link0}
      id: shelf
      primitives:
        - type: box
          dimensions: [0.3, 0.6, 0.04]
      primitive_poses:
        - position: [0.6, -0.1, 0.3]
          orientation: [0, 0, 0.3826834, 0.9238795]
    - header: {frame_id: panda_link0}
      id: can
      primitives:
        - {type: 3, dimensions: [0.2, 0.03]}
      primitive_poses:
        - position: {x: 0.5, y: 0.4, z: 0.1}
          orientation: {x: 0.258819, y: 0, z: 0, w: 0.9659258}
    - header: {frame_id: panda_link0}
      id: ball
      primitives:
        - type: sphere
          dimensions: [0.05]
      primitive_poses:
        - position: [-0.4, 0.3, 0.6]
          orientation: [0, 0, 0, 1]
)";

/// The pose of an obstacle geom as MuJoCo places it: position, rotation, size.
struct GeomPose {
  Eigen::Vector3d position;
  Eigen::Matrix3d rotation;
  Eigen::Vector3d size;
};

GeomPose MujocoGeom(const sim::FrankaModel& model, const std::string& name) {
  const mjModel& m = model.mj();
  auto d = sim::MakeData(m);
  mj_kinematics(&m, d.get());
  const int id = mj_name2id(&m, mjOBJ_GEOM, name.c_str());
  EXPECT_GE(id, 0) << name;
  GeomPose pose;
  pose.position = Eigen::Map<const Eigen::Vector3d>(d->geom_xpos + 3 * id);
  pose.rotation = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(d->geom_xmat + 9 * id);
  pose.size = Eigen::Map<const Eigen::Vector3d>(m.geom_size + 3 * id);
  return pose;
}

TEST(MoveItImportTest, ShapesLandWhereMoveItPutsThem) {
  const NamedScene read = ReadMoveItScene(Write("scene.yaml", kScene), Options());
  ASSERT_EQ(read.scene.boxes.size(), 1u);
  ASSERT_EQ(read.scene.cylinders.size(), 1u);
  ASSERT_EQ(read.scene.spheres.size(), 1u);
  EXPECT_THAT(read.names, ::testing::ElementsAre("ball", "shelf", "can"));  // spheres, boxes, cylinders

  // MuJoCo's placement of the imported shapes against MoveIt's poses read by Eigen.
  const sim::FrankaModel model = sim::MakeFrankaScene(read.scene, 0.001);
  const GeomPose ball = MujocoGeom(model, "obstacle0");
  EXPECT_LT((ball.position - Eigen::Vector3d(-0.4, 0.3, 0.6)).norm(), 1e-9);
  EXPECT_NEAR(ball.size[0], 0.05, 1e-12);

  const GeomPose shelf = MujocoGeom(model, "obstacle1");
  const Eigen::Matrix3d shelf_rotation = Eigen::Quaterniond(0.9238795, 0, 0, 0.3826834).normalized().toRotationMatrix();
  EXPECT_LT((shelf.position - Eigen::Vector3d(0.6, -0.1, 0.3)).norm(), 1e-9);
  EXPECT_LT((shelf.rotation - shelf_rotation).norm(), 1e-6);
  EXPECT_LT((shelf.size - Eigen::Vector3d(0.15, 0.3, 0.02)).norm(), 1e-12);  // half sides

  const GeomPose can = MujocoGeom(model, "obstacle2");
  const Eigen::Matrix3d can_rotation = Eigen::Quaterniond(0.9659258, 0.258819, 0, 0).normalized().toRotationMatrix();
  EXPECT_LT((can.position - Eigen::Vector3d(0.5, 0.4, 0.1)).norm(), 1e-9);
  EXPECT_LT((can.rotation - can_rotation).norm(), 1e-6);
  EXPECT_NEAR(can.size[0], 0.03, 1e-12);  // radius
  EXPECT_NEAR(can.size[1], 0.1, 1e-12);   // half height (MoveIt's dimensions are [height, radius])
}

TEST(MoveItImportTest, AnObjectPoseCarriesItsPrimitives) {
  // MoveIt 2: primitive poses are relative to the object's pose. Two boxes on
  // an object turned 90° about z and moved to (1, 0, 0.5).
  const std::string path = Write("scene.yaml", R"(world:
  collision_objects:
    - id: frame
      header: {frame_id: world}
      pose: {position: [1, 0, 0.5], orientation: [0, 0, 0.7071068, 0.7071068]}
      primitives: [{type: box, dimensions: [0.1, 0.1, 0.1]}, {type: box, dimensions: [0.2, 0.2, 0.2]}]
      primitive_poses:
        - {position: [0.2, 0, 0]}
        - {position: [0, 0.3, 0], orientation: [0, 0, 0.7071068, 0.7071068]}
)");
  const NamedScene read = ReadMoveItScene(path, Options());
  EXPECT_THAT(read.names, ::testing::ElementsAre("frame[0]", "frame[1]"));
  const sim::FrankaModel model = sim::MakeFrankaScene(read.scene, 0.001);
  const Eigen::Quaterniond turn(0.7071068, 0, 0, 0.7071068);
  const Eigen::Vector3d origin(1, 0, 0.5);
  const GeomPose first = MujocoGeom(model, "obstacle0");
  const GeomPose second = MujocoGeom(model, "obstacle1");
  EXPECT_LT((first.position - (origin + turn.normalized() * Eigen::Vector3d(0.2, 0, 0))).norm(), 1e-6);
  EXPECT_LT((second.position - (origin + turn.normalized() * Eigen::Vector3d(0, 0.3, 0))).norm(), 1e-6);
  EXPECT_LT((second.rotation - (turn * turn).normalized().toRotationMatrix()).norm(), 1e-6);  // 180° about z
}

TEST(MoveItImportTest, AnAllZeroOrientationIsTheIdentityAsInMoveIt) {
  const std::string path = Write("scene.yaml", R"(world:
  collision_objects:
    - id: unset
      pose: {position: [0.1, 0, 0], orientation: [0, 0, 0, 0]}
      primitives: [{type: box, dimensions: [0.1, 0.2, 0.3]}]
      primitive_poses: [{position: [0.5, 0, 0.2], orientation: {x: 0, y: 0, z: 0, w: 0}}]
)");
  const NamedScene read = ReadMoveItScene(path, Options());
  ASSERT_EQ(read.scene.boxes.size(), 1u);
  EXPECT_THAT(read.scene.boxes[0].centre, ::testing::ElementsAre(0.6, 0.0, 0.2));
  EXPECT_THAT(read.scene.boxes[0].quaternion, ::testing::ElementsAre(1.0, 0.0, 0.0, 0.0));
}

TEST(MoveItImportTest, JointsAreMatchedByNameAndTheTcpIsMujocos) {
  const std::string scene = Write("scene.yaml", kScene);
  const std::string request = Write("request.yaml", Request(kStart, kGoal));
  MoveItImportOptions options = Options();
  options.grasp = GraspRule::kNone;
  const Problem p = ImportMoveItProblem(Franka(), scene, request, "one", options);
  for (size_t j = 0; j < 7; ++j) {
    EXPECT_NEAR(p.start_q[j], kStart[j], 1e-6) << j;
    EXPECT_NEAR(p.goal_q[j], kGoal[j], 1e-6) << j;
  }
  const sim::FrankaModel model = sim::LoadFrankaModel();
  const Eigen::Vector3d start_tcp = sim::FrankaForwardKinematics(model, p.start_q).tcp_position;
  const Eigen::Vector3d goal_tcp = sim::FrankaForwardKinematics(model, p.goal_q).tcp_position;
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(p.start_tcp[k], start_tcp[k], 1e-6);
    EXPECT_NEAR(p.goal_tcp[k], goal_tcp[k], 1e-6);
  }
  EXPECT_EQ(p.scene.size(), 3);
  EXPECT_TRUE(p.left_out.empty());

  // Wrapped under `request:`, and without a start_state (the scene's robot_state is the start).
  std::string wrapped = "request:\n";
  std::istringstream lines(Request(kGoal, kStart));
  int index = 0;
  for (std::string line; std::getline(lines, line); ++index) {
    if (index >= 4) wrapped += "  " + line + "\n";  // lines 0-3 are the start_state
  }
  std::string with_state = std::string(kScene) + "robot_state:\n  joint_state:\n    name: [";
  for (int j = 0; j < 7; ++j) with_state += std::string(j ? ", " : "") + "panda_joint" + std::to_string(j + 1);
  with_state += "]\n    position: [";
  for (int j = 0; j < 7; ++j) with_state += std::string(j ? ", " : "") + std::to_string(kGoal[j]);
  with_state += "]\n";
  const Problem q = ImportMoveItProblem(Franka(), Write("scene2.yaml", with_state), Write("request2.yaml", wrapped),
                                        "two", options);
  for (size_t j = 0; j < 7; ++j) {
    EXPECT_NEAR(q.start_q[j], kGoal[j], 1e-6) << j;
    EXPECT_NEAR(q.goal_q[j], kStart[j], 1e-6) << j;
  }
}

TEST(MoveItImportTest, TheObjectTheGoalGraspsIsLeftOut) {
  // A can centred on the goal's TCP (MuJoCo's), a table well below it.
  const Eigen::Vector3d tcp = sim::FrankaForwardKinematics(sim::LoadFrankaModel(), kGoal).tcp_position;
  char text[1024];
  std::snprintf(text, sizeof(text), R"(world:
  collision_objects:
    - id: table
      primitives: [{type: box, dimensions: [1.0, 1.0, 0.04]}]
      primitive_poses: [{position: [0.5, 0, -0.3], orientation: [0, 0, 0, 1]}]
    - id: target_can
      primitives: [{type: cylinder, dimensions: [0.12, 0.04]}]
      primitive_poses: [{position: [%.9f, %.9f, %.9f], orientation: [0, 0, 0, 1]}]
)",
                tcp.x(), tcp.y(), tcp.z());
  const std::string scene = Write("scene.yaml", text);
  const std::string request = Write("request.yaml", Request(kStart, kGoal));

  const Problem grasped = ImportMoveItProblem(Franka(), scene, request, "p", Options());
  EXPECT_THAT(grasped.left_out, ::testing::ElementsAre("target_can"));
  EXPECT_THAT(grasped.obstacle_names, ::testing::ElementsAre("table"));
  EXPECT_EQ(grasped.scene.boxes.size(), 1u);
  EXPECT_TRUE(grasped.scene.cylinders.empty());
  EXPECT_GT(grasped.goal_clearance, 0.0);

  MoveItImportOptions keep = Options();
  keep.grasp = GraspRule::kNone;
  const Problem kept = ImportMoveItProblem(Franka(), scene, request, "p", keep);
  EXPECT_TRUE(kept.left_out.empty());
  EXPECT_EQ(kept.scene.size(), 2);
  EXPECT_LT(kept.goal_clearance, 0.0);  // the hand is in the can
}

struct Malformed {
  const char* name;
  std::string scene;    // empty: kScene
  std::string request;  // empty: a good request
  std::string message;  // what the one error must say, after the file's name
};

class MoveItImportMalformedTest : public ::testing::TestWithParam<Malformed> {};

TEST_P(MoveItImportMalformedTest, OneErrorNamesTheFileAndTheEntry) {
  const Malformed& c = GetParam();
  const std::string scene = Write("scene.yaml", c.scene.empty() ? kScene : c.scene);
  const std::string request = Write("request.yaml", c.request.empty() ? Request(kStart, kGoal) : c.request);
  try {
    ImportMoveItProblem(Franka(), scene, request, "p", Options());
    FAIL() << "no error";
  } catch (const Error& e) {
    const std::string file = c.message.rfind("request", 0) == 0 ? request : scene;
    EXPECT_THAT(e.what(), ::testing::HasSubstr(file + ": " + c.message.substr(c.message.find(':') + 2)));
  }
}

std::string Object(const std::string& body) {
  return "world:\n  collision_objects:\n    - id: thing\n" + body;
}

INSTANTIATE_TEST_SUITE_P(
    Cases, MoveItImportMalformedTest,
    ::testing::Values(
        Malformed{"BoxDims", Object("      primitives: [{type: box, dimensions: [0.1, 0.2]}]\n"
                                    "      primitive_poses: [{position: [0, 0, 0]}]\n"),
                  "", "scene: world.collision_objects[0] (thing).primitives[0].dimensions: a box needs 3 values"},
        Malformed{"CylinderDims", Object("      primitives: [{type: cylinder, dimensions: [0.1]}]\n"
                                         "      primitive_poses: [{position: [0, 0, 0]}]\n"),
                  "", "scene: world.collision_objects[0] (thing).primitives[0].dimensions: a cylinder needs 2 values"},
        Malformed{"UnknownType", Object("      primitives: [{type: torus, dimensions: [0.1]}]\n"
                                        "      primitive_poses: [{position: [0, 0, 0]}]\n"),
                  "", "scene: world.collision_objects[0] (thing).primitives[0].type: unknown primitive type \"torus\""},
        Malformed{"PoseCount", Object("      primitives: [{type: sphere, dimensions: [0.1]}]\n"),
                  "", "scene: world.collision_objects[0] (thing).primitive_poses: expected one pose per primitive"},
        Malformed{"BadNumber", Object("      primitives: [{type: sphere, dimensions: [0.1]}]\n"
                                      "      primitive_poses: [{position: [0, zero, 0]}]\n"),
                  "", "scene: world.collision_objects[0] (thing).primitive_poses[0].position[1]: expected a number"},
        Malformed{"Mesh", Object("      meshes: [{vertices: []}]\n      primitives: [{type: sphere, dimensions: [0.1]}]\n"
                                 "      primitive_poses: [{position: [0, 0, 0]}]\n"),
                  "", "scene: world.collision_objects[0] (thing).meshes: meshes are not imported"},
        Malformed{"OtherFrame", Object("      header: {frame_id: camera}\n"
                                       "      primitives: [{type: sphere, dimensions: [0.1]}]\n"
                                       "      primitive_poses: [{position: [0, 0, 0]}]\n"),
                  "", "scene: world.collision_objects[0] (thing).header.frame_id: \"camera\" is neither the robot's base, the world "
                      "nor a fixed frame"},
        Malformed{"NoId", "world:\n  collision_objects:\n    - primitives: []\n", "",
                  "scene: world.collision_objects[0].id: missing"},
        Malformed{"NotAScene", "name: nothing\n", "", "scene: world: missing"},
        Malformed{"MissingGoalJoint", "",
                  "start_state: {joint_state: {name: [panda_joint1, panda_joint2, panda_joint3, panda_joint4, "
                  "panda_joint5, panda_joint6, panda_joint7], position: [0, -0.3, 0, -2.2, 0, 2, 0.8]}}\n"
                  "goal_constraints: [{joint_constraints: [{joint_name: panda_joint1, position: 0.2}]}]\n",
                  "request: goal_constraints[0].joint_constraints: no constraint on panda_joint2"},
        Malformed{"ShortStart", "",
                  "start_state: {joint_state: {name: [panda_joint1], position: [0]}}\n"
                  "goal_constraints: [{position_constraints: [{link_name: panda_hand}]}]\n",
                  "request: start_state.joint_state: no position for panda_joint2"},
        Malformed{"OnlyPoseGoal", "",
                  "start_state: {joint_state: {name: [panda_joint1, panda_joint2, panda_joint3, panda_joint4, "
                  "panda_joint5, panda_joint6, panda_joint7], position: [0, -0.3, 0, -2.2, 0, 2, 0.8]}}\n"
                  "goal_constraints: [{position_constraints: [{link_name: panda_hand}]}]\n",
                  "request: goal_constraints[0].joint_constraints: missing: only joint-space goals are imported"},
        Malformed{"GoalNotAMapping", "",
                  "start_state: {joint_state: {name: [panda_joint1, panda_joint2, panda_joint3, panda_joint4, "
                  "panda_joint5, panda_joint6, panda_joint7], position: [0, -0.3, 0, -2.2, 0, 2, 0.8]}}\n"
                  "goal_constraints: [5]\n",
                  "request: goal_constraints[0]: expected a mapping with joint_constraints"},
        Malformed{"HeaderNotAMapping", Object("      header: 5\n      primitives: [{type: sphere, dimensions: [0.1]}]\n"
                                              "      primitive_poses: [{position: [0, 0, 0]}]\n"),
                  "", "scene: world.collision_objects[0] (thing).header: expected a mapping with frame_id"},
        Malformed{"JointStateNotAMapping", "", "start_state: {joint_state: 5}\ngoal_constraints: []\n",
                  "request: start_state.joint_state: expected a mapping with name and position"},
        Malformed{"NamesPositions", "",
                  "start_state: {joint_state: {name: [panda_joint1, panda_joint2], position: [0]}}\n"
                  "goal_constraints: []\n",
                  "request: start_state.joint_state: 2 names but 1 positions"}),
    [](const ::testing::TestParamInfo<Malformed>& info) { return std::string(info.param.name); });

TEST(MoveItImportTest, AnIdentityVirtualJointIsTheBaseFrame) {
  // MotionBenchMaker's Panda scenes carry the virtual joint at the identity (and an unset rotation is too).
  const std::string request = Write("request.yaml", Request(kStart, kGoal));
  const Problem plain = ImportMoveItProblem(Franka(), Write("scene.yaml", kScene), request, "p", Options());
  for (const char* rotation : {"{x: 0, y: 0, z: 0, w: 1}", "{x: 0, y: 0, z: 0, w: 0}"}) {
    const std::string scene = Write("scene_virtual.yaml", std::string("robot_state:\n  multi_dof_joint_state:\n"
                                                                      "    joint_names: [virtual_joint]\n"
                                                                      "    transforms: [{translation: {x: 0, y: 0, z: 0}, rotation: ") +
                                                              rotation + "}]\n" + kScene);
    const Problem placed = ImportMoveItProblem(Franka(), scene, request, "p", Options());
    EXPECT_EQ(placed.obstacle_names, plain.obstacle_names);
    EXPECT_EQ(placed.scene.size(), plain.scene.size());
    EXPECT_EQ(placed.start_q, plain.start_q);
  }
}

TEST(MoveItImportTest, AStartOrGoalPastALimitIsMovedOntoItWithinTheToleranceAndRefusedBeyond) {
  const auto& d = Franka().description();
  const std::string scene = Write("scene.yaml", kScene);
  std::vector<double> at = kGoal, just = kGoal, past = kGoal;
  at[3] = d.joint_upper[3];           // exactly at the limit, as MotionBenchMaker writes many
  just[3] = d.joint_upper[3] + 0.0014;  // MotionBenchMaker's table_pick goal: 1.4 mrad past it
  past[3] = d.joint_upper[3] + 0.01;
  const Problem on = ImportMoveItProblem(Franka(), scene, Write("r1.yaml", Request(kStart, at)), "on", Options());
  EXPECT_EQ(on.status, "ok");
  EXPECT_EQ(on.goal_q[3], d.joint_upper[3]);
  EXPECT_TRUE(on.notes.empty());
  const Problem moved = ImportMoveItProblem(Franka(), scene, Write("r2.yaml", Request(kStart, just)), "moved", Options());
  EXPECT_EQ(moved.status, "ok");
  EXPECT_EQ(moved.goal_q[3], d.joint_upper[3]);
  ASSERT_EQ(moved.notes.size(), 1u);
  EXPECT_THAT(moved.notes[0], HasSubstr("goal: panda_joint4 = -0.0684 is 0.0014 past its upper limit -0.0698; moved onto "
                                        "the limit"));
  const Problem refused = ImportMoveItProblem(Franka(), scene, Write("r3.yaml", Request(kStart, past)), "past", Options());
  EXPECT_EQ(refused.status, "refused");
  EXPECT_THAT(refused.reason, HasSubstr("goal: panda_joint4 = -0.0598 is 0.01 past its upper limit -0.0698 (more than "
                                        "the tolerance 0.002)"));
  EXPECT_EQ(refused.goal_q[3], past[3]);  // as the file gives it
  MoveItImportOptions strict = Options();
  strict.limit_tolerance = 0.001;
  EXPECT_EQ(ImportMoveItProblem(Franka(), scene, Write("r4.yaml", Request(kStart, just)), "s", strict).status, "refused");
}

TEST(MoveItImportTest, AStartInAnObstacleIsRefusedAndTheFingersAreHeldAsTheFileHoldsThem) {
  // A box around the start's hand; the request holds the fingers 4 cm open (Request writes 0.04 for the first).
  double tcp[3];
  Franka().Tcp(kStart.data(), tcp);
  char text[512];
  std::snprintf(text, sizeof(text), R"(world:
  collision_objects:
    - id: block
      primitives: [{type: box, dimensions: [0.1, 0.1, 0.1]}]
      primitive_poses: [{position: [%.9f, %.9f, %.9f], orientation: [0, 0, 0, 1]}]
)",
                tcp[0], tcp[1], tcp[2]);
  MoveItImportOptions keep = Options();
  keep.grasp = GraspRule::kNone;
  const Problem p = ImportMoveItProblem(Franka(), Write("scene.yaml", text), Write("request.yaml", Request(kStart, kGoal)),
                                        "p", keep);
  EXPECT_EQ(p.status, "refused");
  EXPECT_THAT(p.reason, HasSubstr("start: sphere"));
  EXPECT_THAT(p.reason, HasSubstr("from obstacle 0 (block)"));
  ASSERT_EQ(p.held.size(), 1u);
  EXPECT_EQ(p.held[0].joint, "panda_finger_joint1");
  EXPECT_EQ(p.held[0].value, 0.04);
  EXPECT_EQ(p.floor_height, -INFINITY);  // MoveIt scenes have no floor
  const Problem fine = ImportMoveItProblem(Franka(), Write("scene2.yaml", kScene),
                                           Write("request2.yaml", Request(kStart, kGoal)), "fine", keep);
  EXPECT_EQ(fine.status, "ok");
  EXPECT_EQ(fine.reason, "");
}

TEST(MoveItImportTest, TheObstaclesOfARobotPlacedByItsVirtualJointAreMovedIntoItsBaseFrame) {
  // The base stands at (0.2, -0.1, 0.05) turned 90° about z; a sphere in the world frame, a box in the base frame
  // (panda_link0) and a cylinder in a fixed frame 1 m up.
  const std::string scene = Write("scene.yaml", R"(robot_state:
  multi_dof_joint_state:
    joint_names: [virtual_joint]
    transforms: [{translation: [0.2, -0.1, 0.05], rotation: [0, 0, 0.7071067811865476, 0.7071067811865476]}]
fixed_frame_transforms:
  - child_frame_id: shelf_frame
    transform: {translation: [0, 0, 1], rotation: [0, 0, 0, 1]}
world:
  collision_objects:
    - id: ball
      header: {frame_id: world}
      primitives: [{type: sphere, dimensions: [0.05]}]
      primitive_poses: [{position: [0.7, -0.1, 0.55], orientation: [0, 0, 0, 1]}]
    - id: crate
      header: {frame_id: panda_link0}
      primitives: [{type: box, dimensions: [0.1, 0.2, 0.3]}]
      primitive_poses: [{position: [0.5, 0, 0.1], orientation: [0, 0, 0, 1]}]
    - id: post
      header: {frame_id: shelf_frame}
      primitives: [{type: cylinder, dimensions: [0.2, 0.02]}]
      primitive_poses: [{position: [0.2, 0.4, 0], orientation: [0, 0, 0, 1]}]
)");
  MoveItImportOptions keep = Options();
  keep.grasp = GraspRule::kNone;
  const Problem p = ImportMoveItProblem(Franka(), scene, Write("request.yaml", Request(kStart, kGoal)), "p", keep);
  const Eigen::Isometry3d base = Eigen::Translation3d(0.2, -0.1, 0.05) *
                                 Eigen::Quaterniond(0.7071067811865476, 0, 0, 0.7071067811865476);
  ASSERT_EQ(p.scene.spheres.size(), 1u);
  const Eigen::Vector3d ball = base.inverse() * Eigen::Vector3d(0.7, -0.1, 0.55);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(p.scene.spheres[0].centre[i], ball[i], 1e-12);
  ASSERT_EQ(p.scene.boxes.size(), 1u);
  EXPECT_THAT(p.scene.boxes[0].centre, ::testing::ElementsAre(0.5, 0.0, 0.1));
  ASSERT_EQ(p.scene.cylinders.size(), 1u);
  const Eigen::Vector3d post = base.inverse() * Eigen::Vector3d(0.2, 0.4, 1.0);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(p.scene.cylinders[0].centre[i], post[i], 1e-12);
  // The cylinder's axis, world z, is still the base's z (a turn about z).
  const Eigen::Quaterniond q(p.scene.cylinders[0].quaternion[0], p.scene.cylinders[0].quaternion[1],
                             p.scene.cylinders[0].quaternion[2], p.scene.cylinders[0].quaternion[3]);
  EXPECT_LT((q * Eigen::Vector3d::UnitZ() - Eigen::Vector3d::UnitZ()).norm(), 1e-12);
  EXPECT_THAT(p.base_pose, ::testing::ElementsAre(0.2, -0.1, 0.05, 0.7071067811865476, 0.0, 0.0, 0.7071067811865476));
}

TEST(MoveItImportTest, PairsAreFoundByNumber) {
  const auto dir = flowplan::testing::ScratchDir() / "set";
  std::filesystem::create_directories(dir);
  for (const char* name : {"scene9.yaml", "request9.yaml", "scene10.yaml", "request10.yaml", "scene_sensed9.yaml",
                           "notes.txt"}) {
    std::ofstream(dir / name) << "x: 1\n";
  }
  const auto pairs = FindMoveItPairs(dir.string());
  ASSERT_EQ(pairs.size(), 2u);
  EXPECT_EQ(std::filesystem::path(pairs[0].first).filename(), "scene9.yaml");
  EXPECT_EQ(std::filesystem::path(pairs[1].second).filename(), "request10.yaml");
  std::filesystem::remove(dir / "request10.yaml");
  EXPECT_THROW(
      {
        try {
          FindMoveItPairs(dir.string());
        } catch (const Error& e) {
          EXPECT_THAT(e.what(), ::testing::HasSubstr("scene10.yaml: no request10.yaml beside it"));
          throw;
        }
      },
      Error);
}

}  // namespace
}  // namespace flowplan::problems
