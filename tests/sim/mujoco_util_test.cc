#include "sim/mujoco_util.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <string>
#include <utility>

#include "core/random.h"

namespace flowplan::sim {
namespace {

constexpr const char* kPendulum =
    "<mujoco><worldbody><body pos='0 0 1'><joint type='hinge' axis='0 1 0'/>"
    "<geom type='capsule' fromto='0 0 0 0 0 -0.5' size='0.05'/></body></worldbody></mujoco>";

TEST(MujocoUtilTest, HandlersAreInstalled) {
  InstallMujocoHandlers();
  EXPECT_NE(mju_user_error, nullptr);
  EXPECT_NE(mju_user_warning, nullptr);
}

TEST(MujocoUtilDeathTest, ErrorsEndTheProcessWithStatusOneInsteadOfWaitingForEnter) {
  // The handler logs to the console logger (stdout), so only the exit status is checked.
  EXPECT_EXIT(
      {
        InstallMujocoHandlers();
        mju_error("broken");
      },
      ::testing::ExitedWithCode(1), "");
}

TEST(MujocoUtilTest, BadStateIsCountedAsAnInstabilityWarning) {
  InstallMujocoHandlers();
  MjModelPtr m = LoadModelFromXml(kPendulum, "pendulum");
  MjDataPtr d = MakeData(*m);
  EXPECT_EQ(WarningCount(*d), 0);
  d->qvel[0] = NAN;
  mj_step(m.get(), d.get());
  EXPECT_TRUE(HasInstabilityWarning(*d));
  EXPECT_GE(WarningCount(*d), 1);
  mj_resetData(m.get(), d.get());
  EXPECT_EQ(WarningCount(*d), 0);
}

TEST(MujocoUtilTest, CopiesAreIndependent) {
  MjModelPtr m = LoadModelFromXml(kPendulum, "pendulum");
  MjModelPtr copy = CopyModel(*m);
  copy->opt.timestep = 0.5;
  EXPECT_NE(m->opt.timestep, 0.5);
}

/// The deepest contact distance (0 if none is negative) MuJoCo reports between a board, whose geom has `margin`, and
/// a gripper-sized box (half sides 0.045, 0.065, 0.035) at `pos` turned by `quat` (w, x, y, z); and whether the same
/// pair at margin 0 touches at all.
std::pair<double, bool> BoardAndBox(const std::string& board, const std::string& pos, const std::string& quat) {
  auto xml = [&](double margin) {
    return "<mujoco><worldbody>" + board + " margin='" + std::to_string(margin) + "' gap='" + std::to_string(margin) +
           "' contype='0' conaffinity='1'/><body pos='" + pos + "' quat='" + quat +
           "'><joint type='free'/><geom type='box' size='0.045 0.065 0.035' contype='1' conaffinity='0'/>"
           "</body></worldbody></mujoco>";
  };
  MjModelPtr wide = LoadModelFromXml(xml(0.5), "wide margin");
  MjModelPtr exact = LoadModelFromXml(xml(0.0), "no margin");
  MjDataPtr dw = MakeData(*wide), de = MakeData(*exact);
  mj_forward(wide.get(), dw.get());
  mj_forward(exact.get(), de.get());
  double deepest = 0.0;
  for (int c = 0; c < dw->ncon; ++c) deepest = std::min(deepest, static_cast<double>(dw->contact[c].dist));
  return {deepest, de->ncon > 0};
}

// MuJoCo's box-box collider, asked for contacts within a large margin (the execution models' 0.5 m), can report an
// overlap between boxes that are apart: a gripper box 13 cm above a shelf board (a pose from the arm on a lift's
// shelf problem 2, `plan --execute`) came back 13.4 cm deep. With InstallExactConvexOverlaps every overlap is checked
// again at margin 0; the margin model then agrees with the exact one on random poses too.
TEST(MujocoUtilTest, BoxesWithinAWideMarginOverlapOnlyWhenTheyDo) {
  InstallExactConvexOverlaps();
  const std::string shelf_board =
      "<geom type='box' size='0.227935123 0.539391867 0.0117634037' pos='0.968390087 -0.471364185 0.919920002' "
      "quat='0.974459273 0 0 -0.224564302'";
  const auto [deepest, touching] =
      BoardAndBox(shelf_board, "0.749027587 -0.244597718 1.06405315", "0.592589699 0.692353472 -0.265490825 0.314640652");
  EXPECT_FALSE(touching);
  EXPECT_EQ(deepest, 0.0);
  Rng rng(7);
  int apart = 0, overlapping = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const double x = rng.Uniform(-0.45, 0.45), y = rng.Uniform(-0.35, 0.35), z = rng.Uniform(-0.15, 0.15);
    Eigen::Quaterniond q(rng.Uniform(-1, 1), rng.Uniform(-1, 1), rng.Uniform(-1, 1), rng.Uniform(-1, 1));
    q.normalize();
    const auto [d, t] = BoardAndBox("<geom type='box' size='0.3 0.2 0.01'",
                                    std::to_string(x) + " " + std::to_string(y) + " " + std::to_string(z),
                                    std::to_string(q.w()) + " " + std::to_string(q.x()) + " " + std::to_string(q.y()) +
                                        " " + std::to_string(q.z()));
    if (!t) {
      ++apart;
      EXPECT_EQ(d, 0.0) << "trial " << trial;
    } else {
      ++overlapping;
      EXPECT_LT(d, 0.0) << "trial " << trial;
    }
  }
  EXPECT_GT(apart, 30);
  EXPECT_GT(overlapping, 30);
}

}  // namespace
}  // namespace flowplan::sim
