#include "datasets/trajectory_dataset.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>

#include "core/atomic_file.h"
#include "core/error.h"
#include "datasets/h5.h"
#include "tests/support/scratch_dir.h"

namespace flowplan::datasets {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

TrajectoryDataset SmallDataset() {
  TrajectoryDataset d;
  d.info.env = "particle";
  d.info.dt = 0.05;
  d.info.state_labels = {"x", "y", "vx", "vy"};
  d.info.robot = kinematics::PointRobot("disc", 2, 0.03, 0.0, 1.0);
  d.num_episodes = 3;
  d.info.horizon = 5;
  for (int i = 0; i < 3 * 5 * 4; ++i) d.states.push_back(0.25f * static_cast<float>(i) - 3.0f);
  d.point_dim = 2;
  d.commanded_start = {0, 0, 0, 1, 0, 0};
  d.commanded_goal = {1, 1, 1, 0, 1, 1};
  d.family = {0, 1, 0};
  d.extras["tcp"] = {{3, 5, 3}, std::vector<float>(45, 0.5f)};
  d.train_pairs = {{1, 2, 3, 4}, {5, 6, 7, 8}, {"(0,0)->(1,1)"}};
  d.test_pairs = {{1, 2, 3, 4, 9, 9, 9, 9}, {5, 6, 7, 8, 0, 0, 0, 0}, {"a->b", "c->d"}};
  d.config_yaml = "seed: 3\n";
  d.seed = 3;
  d.first_episode = 0;
  d.end_episode = 3;
  d.total_episodes = 3;
  d.rejected_episodes = 2;
  d.simulator_warnings = 7;
  return d;
}

TEST(TrajectoryDatasetTest, FingerprintChangesWithTheDataAndNotWithBookkeeping) {
  const TrajectoryDataset d = SmallDataset();
  const std::string print = DatasetFingerprint(d);
  EXPECT_EQ(print.size(), 16u);
  TrajectoryDataset changed = d;
  changed.states[17] += 1e-3f;
  EXPECT_NE(DatasetFingerprint(changed), print);
  changed = d;
  changed.info.robot.point_radius = 0.05;
  EXPECT_NE(DatasetFingerprint(changed), print);
  changed = d;
  changed.test_pairs.goal[0] = 2;
  EXPECT_NE(DatasetFingerprint(changed), print);
  changed = d;
  changed.simulator_warnings = 0;  // does not change what a model learns
  EXPECT_EQ(DatasetFingerprint(changed), print);
}

std::string TempPath(const std::string& name) { return (flowplan::testing::ScratchDir() / name).string(); }

TEST(TrajectoryDatasetTest, RoundTripKeepsEverything) {
  const TrajectoryDataset d = SmallDataset();
  const std::string path = TempPath("round_trip.h5");
  WriteDataset(path, d);
  const TrajectoryDataset back = ReadDataset(path);
  EXPECT_EQ(back.info.env, d.info.env);
  EXPECT_EQ(back.info.dt, d.info.dt);
  EXPECT_EQ(back.info.state_labels, d.info.state_labels);
  EXPECT_EQ(back.num_episodes, 3);
  EXPECT_EQ(back.info.horizon, 5);
  EXPECT_EQ(back.info.state_dim(), 4);
  EXPECT_EQ(back.states, d.states);
  EXPECT_EQ(back.commanded_start, d.commanded_start);
  EXPECT_EQ(back.commanded_goal, d.commanded_goal);
  EXPECT_EQ(back.family, d.family);
  ASSERT_EQ(back.extras.count("tcp"), 1u);
  EXPECT_EQ(back.extras.at("tcp").shape, (std::vector<int64_t>{3, 5, 3}));
  EXPECT_EQ(back.train_pairs.start, d.train_pairs.start);
  EXPECT_EQ(back.test_pairs.goal, d.test_pairs.goal);
  EXPECT_EQ(back.test_pairs.names, d.test_pairs.names);
  EXPECT_EQ(back.config_yaml, d.config_yaml);
  EXPECT_EQ(kinematics::RobotToYaml(back.info.robot), kinematics::RobotToYaml(d.info.robot));
  EXPECT_EQ(back.info.robot.point_radius, 0.03);
  EXPECT_EQ(DatasetFingerprint(back), DatasetFingerprint(d));
  EXPECT_EQ(back.seed, 3u);
  EXPECT_EQ(back.rejected_episodes, 2);
  EXPECT_EQ(back.simulator_warnings, 7);
}

TEST(TrajectoryDatasetTest, SameContentSameBytes) {
  WriteDataset(TempPath("bytes_a.h5"), SmallDataset());
  WriteDataset(TempPath("bytes_b.h5"), SmallDataset());
  EXPECT_EQ(ReadFile(TempPath("bytes_a.h5")), ReadFile(TempPath("bytes_b.h5")));
}

TEST(TrajectoryDatasetTest, MissingFileIsNamed) {
  EXPECT_THAT([] { ReadDataset("/nonexistent/data.h5"); },
              ThrowsMessage<Error>(AllOf(HasSubstr("/nonexistent/data.h5"), HasSubstr("no such file"))));
}

TEST(TrajectoryDatasetTest, ForeignAndTruncatedFilesAreRejected) {
  const std::string text = TempPath("not_hdf5.h5");
  std::ofstream(text) << "hello";
  EXPECT_THAT([&] { ReadDataset(text); }, ThrowsMessage<Error>(AllOf(HasSubstr(text), HasSubstr("not an HDF5 file"))));

  const std::string good = TempPath("to_truncate.h5");
  WriteDataset(good, SmallDataset());
  const std::string bytes = ReadFile(good);
  const std::string cut = TempPath("truncated.h5");
  std::ofstream(cut, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  EXPECT_THROW(ReadDataset(cut), Error);
}

TEST(TrajectoryDatasetTest, AttributeOfTheWrongKindIsAClearError) {
  // An attribute set by another tool to a list instead of a single value.
  const std::string path = TempPath("list_attribute.h5");
  WriteDataset(path, SmallDataset());
  {
    hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    H5Adelete(file, "seed");
    const hsize_t two = 2;
    hid_t space = H5Screate_simple(1, &two, nullptr);
    hid_t attribute = H5Acreate2(file, "seed", H5T_STD_I64LE, space, H5P_DEFAULT, H5P_DEFAULT);
    const int64_t values[2] = {1, 2};
    H5Awrite(attribute, H5T_NATIVE_INT64, values);
    H5Aclose(attribute);
    H5Sclose(space);
    H5Fclose(file);
  }
  EXPECT_THAT([&] { ReadDataset(path); },
              ThrowsMessage<Error>(AllOf(HasSubstr(path), HasSubstr("'seed': expected a single integer"))));
}

TEST(TrajectoryDatasetTest, NonFiniteStateIsNamedByEpisodeStepAndDimension) {
  // A file edited or made by another tool: training on it would fail later
  // with a message that names neither the file nor the place.
  TrajectoryDataset d = SmallDataset();
  d.states[(1 * 5 + 2) * 4 + 3] = std::numeric_limits<float>::quiet_NaN();
  const std::string path = TempPath("nan_state.h5");
  WriteDataset(path, d);
  EXPECT_THAT([&] { ReadDataset(path); },
              ThrowsMessage<Error>(AllOf(HasSubstr(path), HasSubstr("/states"),
                                         HasSubstr("episode 1, step 2, dimension 3 (vy)"))));
}

TEST(TrajectoryDatasetTest, InconsistentDatasetIsNotWritten) {
  TrajectoryDataset d = SmallDataset();
  d.states.pop_back();
  const std::string path = TempPath("inconsistent.h5");
  std::remove(path.c_str());
  EXPECT_THAT([&] { WriteDataset(path, d); }, ThrowsMessage<Error>(HasSubstr("states")));
  EXPECT_FALSE(std::filesystem::exists(path));
  // A per-step array must be (N, T, k).
  TrajectoryDataset flat = SmallDataset();
  flat.extras["tcp"] = {{3, 15}, std::vector<float>(45, 0.5f)};
  EXPECT_THAT([&] { WriteDataset(path, flat); },
              ThrowsMessage<Error>(HasSubstr("/extras/tcp: expected shape (3, 5, k), got (3, 15)")));
  EXPECT_FALSE(std::filesystem::exists(path));
}

TEST(TrajectoryDatasetTest, MergeConcatenatesAndChecksCompatibility) {
  TrajectoryDataset a = SmallDataset();
  a.total_episodes = 6;  // a and b are the halves of a dataset of 6 episodes
  TrajectoryDataset b = a;
  b.first_episode = a.end_episode;
  b.end_episode = a.end_episode + 3;
  const TrajectoryDataset merged = MergeDatasets({a, b}, {"a.h5", "b.h5"});
  EXPECT_EQ(merged.first_episode, 0);
  EXPECT_EQ(merged.end_episode, 6);
  EXPECT_EQ(merged.num_episodes, 6);
  EXPECT_EQ(merged.states.size(), 2 * a.states.size());
  EXPECT_EQ(merged.extras.at("tcp").shape[0], 6);
  EXPECT_EQ(merged.rejected_episodes, 4);
  TrajectoryDataset other = b;
  other.seed = 4;
  EXPECT_THAT([&] { MergeDatasets({a, other}, {"a.h5", "c.h5"}); },
              ThrowsMessage<Error>(AllOf(HasSubstr("c.h5"), HasSubstr("seed"))));
  EXPECT_THAT([&] { MergeDatasets({a, a}, {"a.h5", "a_again.h5"}); },
              ThrowsMessage<Error>(AllOf(HasSubstr("a_again.h5"), HasSubstr("in order, each once"))));
  EXPECT_THAT([&] { MergeDatasets({a}, {"a.h5"}); },
              ThrowsMessage<Error>(HasSubstr("the shards hold episodes [0, 3) of a dataset of 6")));
}

}  // namespace
}  // namespace flowplan::datasets
