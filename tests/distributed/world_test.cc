#include "distributed/world.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <map>
#include <string>

#include "core/error.h"

namespace flowplan::distributed {
namespace {

using ::testing::HasSubstr;

std::optional<World> FromVariables(const std::map<std::string, std::string>& variables) {
  return WorldFromEnvironment([&](const char* name) -> const char* {
    const auto it = variables.find(name);
    return it == variables.end() ? nullptr : it->second.c_str();
  });
}

std::string ErrorOf(const std::map<std::string, std::string>& variables) {
  try {
    FromVariables(variables);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(ProcessWorldTest, NoLauncherOrOneProcessIsNoJob) {
  EXPECT_FALSE(FromVariables({}).has_value());
  EXPECT_FALSE(FromVariables({{"WORLD_SIZE", "1"}, {"RANK", "0"}}).has_value());
  EXPECT_FALSE(FromVariables({{"SLURM_STEP_NUM_TASKS", "1"}, {"SLURM_PROCID", "0"}}).has_value());
  // A batch script or salloc shell of a multi-task allocation (no srun step) is one process.
  EXPECT_FALSE(FromVariables({{"SLURM_NTASKS", "8"}, {"SLURM_PROCID", "0"}, {"MASTER_ADDR", "h"}}).has_value());
}

TEST(ProcessWorldTest, ReadsTorchrunVariables) {
  const auto world = FromVariables({{"RANK", "3"},
                                    {"WORLD_SIZE", "4"},
                                    {"LOCAL_RANK", "1"},
                                    {"LOCAL_WORLD_SIZE", "2"},
                                    {"MASTER_ADDR", "node7"},
                                    {"MASTER_PORT", "29700"},
                                    {"TORCHELASTIC_USE_AGENT_STORE", "True"}});
  ASSERT_TRUE(world.has_value());
  EXPECT_EQ(world->rank, 3);
  EXPECT_EQ(world->size, 4);
  EXPECT_EQ(world->local_rank, 1);
  EXPECT_EQ(world->local_size, 2);
  EXPECT_EQ(world->master_addr, "node7");
  EXPECT_EQ(world->master_port, 29700);
  EXPECT_TRUE(world->agent_hosts_store);
  EXPECT_EQ(world->source, "torchrun");
}

TEST(ProcessWorldTest, ReadsSlurmVariablesWithDefaults) {
  const auto world = FromVariables({{"SLURM_PROCID", "5"},
                                    {"SLURM_NTASKS", "8"},
                                    {"SLURM_STEP_NUM_TASKS", "8"},
                                    {"SLURM_LOCALID", "1"},
                                    {"SLURM_NTASKS_PER_NODE", "2(x4)"},
                                    {"SLURM_LAUNCH_NODE_IPADDR", "10.0.0.2"}});
  ASSERT_TRUE(world.has_value());
  EXPECT_EQ(world->rank, 5);
  EXPECT_EQ(world->size, 8);
  EXPECT_EQ(world->local_rank, 1);
  EXPECT_EQ(world->local_size, 2);
  EXPECT_EQ(world->master_addr, "10.0.0.2");  // MASTER_ADDR, when set, wins
  EXPECT_EQ(world->master_port, 29500);
  EXPECT_FALSE(world->agent_hosts_store);
  EXPECT_EQ(world->source, "slurm");
  // torchrun's variables win over Slurm's (torchrun inside an allocation).
  EXPECT_EQ(FromVariables({{"SLURM_PROCID", "5"}, {"SLURM_STEP_NUM_TASKS", "8"}, {"RANK", "1"}, {"WORLD_SIZE", "2"},
                           {"MASTER_ADDR", "127.0.0.1"}})->rank,
            1);
}

TEST(ProcessWorldTest, NamesTheVariableAtFault) {
  EXPECT_THAT(ErrorOf({{"WORLD_SIZE", "2"}, {"MASTER_ADDR", "h"}}), HasSubstr("RANK is not set"));
  EXPECT_THAT(ErrorOf({{"WORLD_SIZE", "2"}, {"RANK", "2"}, {"MASTER_ADDR", "h"}}), HasSubstr("RANK=2"));
  EXPECT_THAT(ErrorOf({{"WORLD_SIZE", "two"}}), HasSubstr("WORLD_SIZE=two"));
  EXPECT_THAT(ErrorOf({{"WORLD_SIZE", "2"}, {"RANK", "1"}}), HasSubstr("MASTER_ADDR is not set"));
  EXPECT_THAT(ErrorOf({{"WORLD_SIZE", "2"}, {"RANK", "1"}, {"MASTER_ADDR", "h"}, {"MASTER_PORT", "70000"}}),
              HasSubstr("MASTER_PORT=70000"));
  EXPECT_THAT(ErrorOf({{"SLURM_STEP_NUM_TASKS", "2"}, {"SLURM_PROCID", "0"}}), HasSubstr("MASTER_ADDR is not set"));
}

}  // namespace
}  // namespace flowplan::distributed
