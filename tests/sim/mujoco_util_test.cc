#include "sim/mujoco_util.h"

#include <gtest/gtest.h>

#include <cmath>

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

}  // namespace
}  // namespace flowplan::sim
