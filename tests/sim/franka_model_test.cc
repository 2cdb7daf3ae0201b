#include "sim/franka_model.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "core/error.h"
#include "spheres/cover.h"
#include "spheres/mesh.h"

namespace flowplan::sim {
namespace {

using ::testing::HasSubstr;

// Franka's modified (Craig) DH table: a_{i-1}, d_i, alpha_{i-1}; row 8 is the flange.
struct DhRow {
  double a, d, alpha;
};
constexpr DhRow kDh[8] = {{0.0, 0.333, 0.0},         {0.0, 0.0, -M_PI / 2},   {0.0, 0.316, M_PI / 2},
                          {0.0825, 0.0, M_PI / 2},   {-0.0825, 0.384, -M_PI / 2}, {0.0, 0.0, M_PI / 2},
                          {0.088, 0.0, M_PI / 2},    {0.0, 0.107, 0.0}};

// Independent forward kinematics: T_i = Rx(alpha) Tx(a) Rz(theta) Tz(d).
std::vector<Eigen::Isometry3d> DhFrames(const JointVector& q) {
  std::vector<Eigen::Isometry3d> frames;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 8; ++i) {
    const double theta = i < 7 ? q[i] : 0.0;
    Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
    step.rotate(Eigen::AngleAxisd(kDh[i].alpha, Eigen::Vector3d::UnitX()));
    step.translate(Eigen::Vector3d(kDh[i].a, 0, 0));
    step.rotate(Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitZ()));
    step.translate(Eigen::Vector3d(0, 0, kDh[i].d));
    pose = pose * step;
    frames.push_back(pose);
  }
  return frames;
}

JointVector RandomConfiguration(const FrankaLimits& limits, std::mt19937_64& gen) {
  JointVector q;
  for (int j = 0; j < kFrankaJoints; ++j) {
    q[j] = std::uniform_real_distribution<double>(limits.q_lower[j], limits.q_upper[j])(gen);
  }
  return q;
}

Eigen::Matrix3d BodyRotation(const mjData& d, int body) {
  return Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(d.xmat + 9 * body);
}

class FrankaModelTest : public ::testing::Test {
 protected:
  FrankaModel model_ = LoadFrankaModel();
};

TEST_F(FrankaModelTest, MujocoKinematicsMatchAnIndependentDhImplementation) {
  MjDataPtr d = MakeData(model_.mj());
  std::mt19937_64 gen(7);
  for (int trial = 0; trial < 200; ++trial) {
    const JointVector q = RandomConfiguration(model_.limits(), gen);
    const FrankaPose pose = FrankaForwardKinematics(model_, *d, q);
    const std::vector<Eigen::Isometry3d> dh = DhFrames(q);
    for (int i = 0; i < 7; ++i) {
      const int body = mj_name2id(&model_.mj(), mjOBJ_BODY, ("link" + std::to_string(i + 1)).c_str());
      const Eigen::Vector3d position = Eigen::Map<const Eigen::Vector3d>(d->xpos + 3 * body);
      EXPECT_LT((position - dh[i].translation()).norm(), 1e-9) << "link " << i + 1;
      EXPECT_LT((BodyRotation(*d, body) - dh[i].rotation()).cwiseAbs().maxCoeff(), 1e-9) << "link " << i + 1;
    }
    EXPECT_LT((pose.flange_position - dh[7].translation()).norm(), 1e-9);
    EXPECT_LT((pose.flange_rotation - dh[7].rotation()).cwiseAbs().maxCoeff(), 1e-9);
    // The TCP is 0.107 m past the flange along the flange z axis.
    const Eigen::Vector3d tcp = dh[7] * Eigen::Vector3d(0, 0, 0.107);
    EXPECT_LT((pose.tcp_position - tcp).norm(), 1e-9);
  }
}

TEST_F(FrankaModelTest, ReadyPoseFlangeIsAtItsPublishedPosition) {
  // Ready pose of libfranka / MoveIt's panda description: flange at (0.306890566, 0, 0.590282052).
  const FrankaPose pose = FrankaForwardKinematics(model_, {0, -M_PI / 4, 0, -3 * M_PI / 4, 0, M_PI / 2, M_PI / 4});
  EXPECT_NEAR(pose.flange_position.x(), 0.306890566, 1e-9);
  EXPECT_NEAR(pose.flange_position.y(), 0.0, 1e-9);
  EXPECT_NEAR(pose.flange_position.z(), 0.590282052, 1e-9);
  EXPECT_NEAR(pose.tcp_position.z(), 0.590282052 - 0.107, 1e-9);
  // The gripper points down with the hand's x axis along world x.
  EXPECT_LT((pose.tcp_rotation - DownwardTcpRotation()).cwiseAbs().maxCoeff(), 1e-9);
}

TEST_F(FrankaModelTest, RoboticsToolboxPoseMatches) {
  // Robotics Toolbox (Python) Panda test pose: its end effector is the flange
  // followed by Tz(0.103) Rz(-pi/4), i.e. our hand frame moved 0.103 m along z.
  MjDataPtr d = MakeData(model_.mj());
  JointVector q;
  q << 1.4, 0.2, 1.8, 0.7, 0.1, 3.1, 2.9;
  FrankaForwardKinematics(model_, *d, q);
  const int hand = model_.hand_body();
  const Eigen::Matrix3d rotation = BodyRotation(*d, hand);
  const Eigen::Vector3d position =
      Eigen::Map<const Eigen::Vector3d>(d->xpos + 3 * hand) + 0.103 * rotation.col(2);
  EXPECT_NEAR(position.x(), 0.44682295, 1e-8);
  EXPECT_NEAR(position.y(), 0.16168396, 1e-8);
  EXPECT_NEAR(position.z(), 0.96798113, 1e-8);
  Eigen::Matrix3d expected;
  expected << -0.50827907, -0.57904589, 0.63746234, 0.83014553, -0.52639462, 0.18375824, 0.22915229,
      0.62258699, 0.74824773;
  EXPECT_LT((rotation - expected).cwiseAbs().maxCoeff(), 1e-8);
}

TEST_F(FrankaModelTest, LimitsAreFrankasPublishedOnes) {
  const FrankaLimits& limits = model_.limits();
  const double upper[7] = {2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973};
  const double lower[7] = {-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973};
  for (int j = 0; j < 7; ++j) {
    EXPECT_EQ(limits.q_upper[j], upper[j]);
    EXPECT_EQ(limits.q_lower[j], lower[j]);
    EXPECT_EQ(limits.velocity[j], j < 4 ? 2.175 : 2.61);
    EXPECT_EQ(limits.torque[j], j < 4 ? 87.0 : 12.0);
  }
  // Nothing collides in simulation.
  for (int g = 0; g < model_.mj().ngeom; ++g) {
    EXPECT_EQ(model_.mj().geom_contype[g], 0);
    EXPECT_EQ(model_.mj().geom_conaffinity[g], 0);
  }
}

TEST_F(FrankaModelTest, FileAndBuiltInModelAreTheSame) {
  const FrankaModel file = LoadFrankaModelFile(std::string(FLOWPLAN_SOURCE_DIR) + "/sim/assets/franka_panda.xml");
  ASSERT_EQ(file.mj().nbody, model_.mj().nbody);
  for (int i = 0; i < 3 * model_.mj().nbody; ++i) EXPECT_EQ(file.mj().body_pos[i], model_.mj().body_pos[i]);
  for (int i = 0; i < model_.mj().nbody; ++i) EXPECT_EQ(file.mj().body_mass[i], model_.mj().body_mass[i]);
  EXPECT_EQ(file.description().spheres.size(), model_.description().spheres.size());
}

TEST_F(FrankaModelTest, CollisionSpheresCoverThePublishedCollisionMeshes) {
  const kinematics::RobotDescription& description = model_.description();
  ASSERT_EQ(description.num_joints, 7);
  ASSERT_EQ(description.links.size(), 11u);  // link0..link7, hand, two fingers
  EXPECT_EQ(description.links[description.tcp_link].name, "hand");
  // Every link's mesh (robots/franka_panda/meshes, in the link's frame) lies inside its spheres, on surface samples
  // the fit never saw, and no sphere reaches far outside it (fitted for 1 cm; 15 mm on the wrist's housing).
  const std::string dir = std::string(FLOWPLAN_SOURCE_DIR) + "/robots/franka_panda/meshes/";
  for (size_t l = 0; l < description.links.size(); ++l) {
    const std::string& name = description.links[l].name;
    const std::string file = name == "left_finger" || name == "right_finger" ? "finger.obj" : name + ".obj";
    std::vector<spheres::Sphere> cover;
    for (const auto& s : description.spheres) {
      if (s.link == static_cast<int>(l)) cover.push_back({s.centre, s.radius});
    }
    ASSERT_FALSE(cover.empty()) << name;
    const spheres::CoverReport report = spheres::CheckCover(spheres::LoadMesh(dir + file), cover, 0.004, 101);
    EXPECT_GT(report.samples, 100) << name;
    EXPECT_EQ(report.uncovered, 0) << name << ": " << report.largest_uncovered << " m outside every sphere";
    EXPECT_LT(report.largest_outside, 0.016) << name;
  }
}

TEST_F(FrankaModelTest, TheFingersAreHeldPrismaticJointsAndTheArmJointsCarryTheirPublishedNames) {
  const kinematics::RobotDescription& description = model_.description();
  for (const auto& link : description.links) {
    if (link.name == "left_finger" || link.name == "right_finger") {
      EXPECT_EQ(link.type, kinematics::JointType::kPrismatic) << link.name;
      EXPECT_EQ(link.joint_name, link.name == "left_finger" ? "panda_finger_joint1" : "panda_finger_joint2");
    }
  }
  for (int j = 0; j < 7; ++j) EXPECT_EQ(description.JointName(j), "panda_joint" + std::to_string(j + 1));
}

TEST(FrankaModelErrorsTest, BrokenXmlNamesTheSourceAndReason) {
  EXPECT_THAT([] { FrankaModel("<mujoco><worldbody><body></mujoco>", "broken.xml"); },
              ::testing::ThrowsMessage<Error>(HasSubstr("broken.xml: MuJoCo cannot load the model")));
  EXPECT_THAT([] { LoadFrankaModelFile("/nonexistent/panda.xml"); },
              ::testing::ThrowsMessage<Error>(HasSubstr("/nonexistent/panda.xml: cannot open model file")));
}

TEST(FrankaModelErrorsTest, AModelThatIsNotTheArmIsRejected) {
  const char* pendulum =
      "<mujoco><worldbody><body><joint type='hinge'/><geom size='0.1'/></body></worldbody></mujoco>";
  EXPECT_THAT([&] { FrankaModel(pendulum, "pendulum.xml"); },
              ::testing::ThrowsMessage<Error>(HasSubstr("pendulum.xml: expected an arm with 7 hinge joints")));
}

TEST(FrankaModelErrorsTest, ForwardKinematicsChecksTheJointCount) {
  const FrankaModel model = LoadFrankaModel();
  EXPECT_THAT([&] { FrankaForwardKinematics(model, std::vector<double>{0, 0, 0}); },
              ::testing::ThrowsMessage<Error>(HasSubstr("q: expected 7 joint values, got 3")));
}

}  // namespace
}  // namespace flowplan::sim
