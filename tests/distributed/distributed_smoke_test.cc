// Data-parallel training with the real `flowplan` binary: processes launched
// by hand with torchrun's environment variables on localhost, compared with a
// single process training the same data parts (the combined batch), resumed,
// and ended cleanly when a peer is missing or dies.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <csignal>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include "tests/support/command.h"
#include "tests/support/scratch_dir.h"

namespace flowplan {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

std::string Shell(const std::string& command, int* exit_code) {
  const flowplan::testing::Outcome outcome = flowplan::testing::RunCommand(command);
  *exit_code = outcome.exit_code;
  return outcome.output;
}

std::string ReadText(const fs::path& path) { return flowplan::testing::ReadText(path.string()); }

/// A TCP port nobody listens on right now.
int FreePort() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = 0;
  bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address));
  socklen_t length = sizeof(address);
  getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length);
  close(fd);
  return ntohs(address.sin_port);
}

class DistributedTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = flowplan::testing::ScratchDir();
    int code = 0;
    const std::string output = Shell(Flowplan() + " generate --config " + Tiny() + " generate.out=" + Path("data.h5") +
                                   " --log-level warn", &code);
    ASSERT_EQ(code, 0) << output;
  }
  static std::string Flowplan() { return FLOWPLAN_BINARY; }
  static std::string Tiny() { return std::string(FLOWPLAN_SOURCE_DIR) + "/tests/cli/tiny.yaml"; }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  /// The training arguments every run here shares: `parts` data parts of 2 gradient shards, 1 thread each.
  std::string Settings(const std::string& run, int parts = 2) const {
    return " data.path=" + Path("data.h5") + " run_dir=" + Path(run) + " train.data_parts=" + std::to_string(parts) +
           " train.shards=2 train.steps=12 train.checkpoint_every=4 threads=1";
  }

  /// Starts `ranks` processes of one job (rank r runs `arguments[r]`), waits for
  /// all, and returns their exit codes; rank r's output goes to log<r>.
  std::vector<int> Launch(int ranks, const std::vector<std::string>& arguments, int port, int world_size = 0) {
    std::string script;
    for (int r = 0; r < ranks; ++r) {
      const std::string n = std::to_string(r);
      script += "RANK=" + n + " WORLD_SIZE=" + std::to_string(world_size > 0 ? world_size : ranks) + " LOCAL_RANK=" +
                n + " MASTER_ADDR=127.0.0.1 MASTER_PORT=" + std::to_string(port) + " " + Flowplan() + " " +
                arguments[r] + " > " + Path("log" + n) + " 2>&1 & p" + n + "=$!; echo $p" + n + " > " +
                Path("pid" + n) + "; ";
    }
    for (int r = 0; r < ranks; ++r) {
      const std::string n = std::to_string(r);
      script += "wait $p" + n + "; echo $? > " + Path("rc" + n) + "; ";
    }
    int code = 0;
    Shell("sh -c '" + script + "'", &code);
    std::vector<int> codes;
    for (int r = 0; r < ranks; ++r) {
      const std::string rc = ReadText(Path("rc" + std::to_string(r)));
      codes.push_back(rc.empty() ? -1 : std::stoi(rc));
    }
    return codes;
  }

  /// The largest difference of the networks' outputs and plans of two runs' exports.
  double MaxOutputDifference(const std::string& run_a, const std::string& run_b) {
    int code = 0;
    for (const std::string& run : {run_a, run_b}) {
      const std::string output = Shell(Flowplan() + " export --ckpt " + Path(run) + " --out " + Path(run + ".pt"), &code);
      EXPECT_EQ(code, 0) << output;
    }
    const std::string output = Shell(std::string(FLOWPLAN_PYTHON) + " " + FLOWPLAN_SOURCE_DIR +
                                         "/tests/distributed/compare_planners.py " + Path(run_a + ".pt") + " " +
                                         Path(run_b + ".pt"), &code);
    EXPECT_EQ(code, 0) << output;
    const size_t velocity = output.find("\"velocity\": "), plan = output.find("\"plan\": ");
    if (code != 0 || velocity == std::string::npos || plan == std::string::npos) return 1e9;
    return std::max(std::stod(output.substr(velocity + 12)), std::stod(output.substr(plan + 8)));
  }

  double MaxWeightDifference(const std::string& a, const std::string& b) {
    int code = 0;
    const std::string output = Shell(std::string(FLOWPLAN_PYTHON) + " " + FLOWPLAN_SOURCE_DIR +
                                       "/tests/distributed/compare_checkpoints.py " + a + " " + b, &code);
    EXPECT_EQ(code, 0) << output;
    const size_t at = output.find("\"max_abs_diff\": ");
    if (code != 0 || at == std::string::npos) return 1e9;
    return std::stod(output.substr(at + 16));
  }

  fs::path dir_;
};

// Summation order is the only difference between one process and several
// (Gloo sums the ranks' gradients, one process adds its parts in order). With
// two parts on two processes both add the same two numbers: the weights are
// bit-identical. With four parts on two processes the order differs, and
// AdamW turns the rounding of gradients that are zero in exact arithmetic (a
// convolution bias before a GroupNorm) into steps of either sign: those
// weights differ, what the networks compute does not (compare_planners.py),
// to this tolerance on outputs in [-1, 1].
constexpr double kTolerance = 1e-5;

TEST_F(DistributedTest, TwoProcessesTrainWhatOneProcessTrainsOnTheCombinedBatch) {
  int code = 0;
  const std::string single = Shell(Flowplan() + " train --config " + Tiny() + Settings("single"), &code);
  ASSERT_EQ(code, 0) << single;
  const std::string args = "train --config " + Tiny() + Settings("pair");
  const std::vector<int> codes = Launch(2, {args, args}, FreePort());
  ASSERT_EQ(codes[0], 0) << ReadText(Path("log0"));
  ASSERT_EQ(codes[1], 0) << ReadText(Path("log1"));
  EXPECT_THAT(ReadText(Path("log0")), HasSubstr("2 data parts over 2 processes"));
  EXPECT_EQ(MaxWeightDifference(Path("single/checkpoints/step_00000012.pt"), Path("pair/checkpoints/step_00000012.pt")),
            0.0);
  // Rank 0 alone writes the run folder: one metrics file with one row per logged step.
  const std::string pair_metrics = ReadText(Path("pair/metrics.jsonl"));
  const std::string single_metrics = ReadText(Path("single/metrics.jsonl"));
  EXPECT_EQ(std::count(pair_metrics.begin(), pair_metrics.end(), '\n'),
            std::count(single_metrics.begin(), single_metrics.end(), '\n'));
  EXPECT_EQ(ReadText(Path("log1")), "");  // the other ranks report warnings and errors only

  // Four parts on two processes (two each), stopped at step 8 and resumed by
  // both, end where one process with four parts does.
  const std::string single4 = Shell(Flowplan() + " train --config " + Tiny() + Settings("single4", 4), &code);
  ASSERT_EQ(code, 0) << single4;
  const std::string first = "train --config " + Tiny() + Settings("resumed", 4) + " --until 8";
  ASSERT_EQ(Launch(2, {first, first}, FreePort()), (std::vector<int>{0, 0})) << ReadText(Path("log0"));
  ASSERT_TRUE(fs::exists(Path("resumed/checkpoints/step_00000008.pt")));
  ASSERT_FALSE(fs::exists(Path("resumed/checkpoints/step_00000012.pt")));
  const std::string again = "train --resume " + Path("resumed");
  ASSERT_EQ(Launch(2, {again, again}, FreePort()), (std::vector<int>{0, 0})) << ReadText(Path("log0"));
  EXPECT_THAT(ReadText(Path("log0")), HasSubstr("resuming"));
  EXPECT_LT(MaxOutputDifference("single4", "resumed"), kTolerance);
  // Rank 0 alone rewrote the metrics on resume: one loss row per logged step, as uninterrupted.
  auto loss_rows = [](const std::string& text) {
    size_t rows = 0;
    for (size_t at = text.find("\"loss\""); at != std::string::npos; at = text.find("\"loss\"", at + 1)) ++rows;
    return rows;
  };
  EXPECT_EQ(loss_rows(ReadText(Path("resumed/metrics.jsonl"))), loss_rows(ReadText(Path("single4/metrics.jsonl"))));
  // And a single process resumes the job's run (the parts, not the processes, make the run).
  const std::string alone = Shell(Flowplan() + " train --resume " + Path("pair") + " train.steps=16", &code);
  EXPECT_EQ(code, 0) << alone;
  EXPECT_TRUE(fs::exists(Path("pair/checkpoints/step_00000016.pt"))) << alone;
}

TEST_F(DistributedTest, AMissingPeerEndsTheJobAfterTheTimeout) {
  const auto started = std::chrono::steady_clock::now();
  const std::vector<int> codes =
      Launch(1, {"train --config " + Tiny() + Settings("alone") + " distributed.timeout_s=3"}, FreePort(), 2);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  EXPECT_EQ(codes[0], 1);
  const std::string log = ReadText(Path("log0"));
  EXPECT_THAT(log, HasSubstr("rank 0 of 2"));
  EXPECT_THAT(log, HasSubstr("distributed.timeout_s=3"));
  EXPECT_LT(seconds, 60.0) << log;
  EXPECT_FALSE(fs::exists(Path("alone/checkpoints"))) << log;
}

TEST_F(DistributedTest, APeerThatDiesEndsTheOthers) {
  const int port = FreePort();
  const std::string args = "train --config " + Tiny() + " data.path=" + Path("data.h5") + " run_dir=" + Path("dies") +
                           " train.data_parts=2 train.steps=1000000 train.log_every=1 threads=1 " +
                           "distributed.timeout_s=600";
  // Rank 1 is killed once rank 0 has logged a step; rank 0 must notice at its next
  // all-reduce, long before the 600 s timeout.
  std::thread killer([&] {
    for (int i = 0; i < 600; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      if (ReadText(Path("log0")).find("step 2/") != std::string::npos) break;
    }
    const std::string pid = ReadText(Path("pid1"));
    if (!pid.empty()) kill(std::stoi(pid), SIGKILL);
  });
  const auto started = std::chrono::steady_clock::now();
  const std::vector<int> codes = Launch(2, {args, args}, port);
  killer.join();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  const std::string log = ReadText(Path("log0"));
  EXPECT_EQ(codes[0], 1) << log;
  // Rank 0 notices in the step's all-reduce, or in a checkpoint's all-gather.
  EXPECT_THAT(log, ::testing::ContainsRegex("rank 0 of 2: all-(reduce|gather) failed: a peer exited")) << log;
  EXPECT_LT(seconds, 120.0) << log;
}

TEST_F(DistributedTest, AChangedDataFileStopsEveryProcessOnResume) {
  const std::string args = "train --config " + Tiny() + Settings("changed") + " --until 4";
  ASSERT_EQ(Launch(2, {args, args}, FreePort()), (std::vector<int>{0, 0})) << ReadText(Path("log0"));
  int code = 0;
  const std::string regenerated = Shell(Flowplan() + " generate --config " + Tiny() + " seed=2 generate.out=" +
                                        Path("data.h5") + " --log-level warn", &code);
  ASSERT_EQ(code, 0) << regenerated;
  // Only rank 0 reads the whole file and can tell; rank 1 reads its episodes only and learns the verdict.
  const std::string again = "train --resume " + Path("changed");
  EXPECT_EQ(Launch(2, {again, again}, FreePort()), (std::vector<int>{1, 1}));
  EXPECT_THAT(ReadText(Path("log0")), HasSubstr("the data file changed since the run started"));
  EXPECT_THAT(ReadText(Path("log1")), HasSubstr("rank 0 found that the data file changed"));
}

TEST_F(DistributedTest, DataPartsMustBeShareableByTheProcesses) {
  const std::string args = "train --config " + Tiny() + " data.path=" + Path("data.h5") + " run_dir=" + Path("odd") +
                           " train.data_parts=3 threads=1";
  const std::vector<int> codes = Launch(2, {args, args}, FreePort());
  EXPECT_EQ(codes[0], 1);
  EXPECT_THAT(ReadText(Path("log0")), HasSubstr("train.data_parts=3 must be a multiple of the number of processes (2)"));
}

}  // namespace
}  // namespace flowplan
