// Running commands (the `flowplan` binary, scripts) from tests: their exit
// status and output, the one-clear-line failure check, and interrupting a
// command once it says it is ready.
#pragma once

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace flowplan::testing {

struct Outcome {
  int exit_code;
  std::string output;  // stdout and stderr
};

/// Runs `command_line` in a shell; its exit status (-1 if it did not exit) and everything it printed.
inline Outcome RunCommand(const std::string& command_line) {
  FILE* pipe = popen((command_line + " 2>&1").c_str(), "r");
  std::string output;
  std::array<char, 4096> buffer;
  while (fgets(buffer.data(), buffer.size(), pipe) != nullptr) output += buffer.data();
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

#ifdef FLOWPLAN_BINARY
/// The built `flowplan` with `arguments`.
inline Outcome Flowplan(const std::string& arguments) { return RunCommand(std::string(FLOWPLAN_BINARY) + " " + arguments); }

/// Starts `flowplan arguments`, waits until its output holds `ready` (at most `timeout_s`), sends SIGINT
/// (Ctrl-C) and waits for it to end: its exit status and output. The wait is for what the command says,
/// not for a time that a slow machine could outlast.
inline Outcome FlowplanInterruptedWhen(const std::string& arguments, const std::string& ready, const std::string& log,
                                       int timeout_s = 120) {
  const std::string script = std::string(FLOWPLAN_BINARY) + " " + arguments + " > '" + log + "' 2>&1 & pid=$!; " +
                             "for i in $(seq " + std::to_string(timeout_s * 20) + "); do grep -qF -- '" + ready + "' '" +
                             log + "' && break; kill -0 $pid 2>/dev/null || break; sleep 0.05; done; " +
                             "kill -INT $pid; wait $pid; status=$?; cat '" + log + "'; exit $status";
  return RunCommand(script);
}
#endif

inline void ExpectOk(const Outcome& outcome) { ASSERT_EQ(outcome.exit_code, 0) << outcome.output; }

/// One clear line naming the problem (it holds `names`), exit status 1, no stack dump.
inline void ExpectCleanFailure(const Outcome& outcome, const std::string& names) {
  EXPECT_EQ(outcome.exit_code, 1) << outcome.output;
  std::vector<std::string> errors;  // lines that are not progress (info) lines
  std::istringstream lines(outcome.output);
  for (std::string line; std::getline(lines, line);) {
    if (line.find("] [info] ") == std::string::npos) errors.push_back(line);
  }
  ASSERT_EQ(errors.size(), 1u) << outcome.output;
  EXPECT_THAT(errors[0], ::testing::HasSubstr("] [error] "));
  EXPECT_THAT(errors[0], ::testing::HasSubstr(names));
}

inline std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/// A path of the source tree.
inline std::string Source(const std::string& path) { return std::string(FLOWPLAN_SOURCE_DIR) + "/" + path; }

}  // namespace flowplan::testing
