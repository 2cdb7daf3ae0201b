#include "core/config.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>

#include "tests/support/scratch_dir.h"

namespace flowplan {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

enum class Mode { kFast, kSlow };
inline const config::EnumNames<Mode>& EnumEntries(Mode) {
  static const config::EnumNames<Mode> names = {{Mode::kFast, "fast"}, {Mode::kSlow, "slow"}};
  return names;
}

struct Inner {
  std::vector<int> dims = {32, 64};
  double lr = 2e-4;
  template <class V>
  void Visit(V& v) {
    v.Field("dims", dims, "channel widths", config::Positive());
    v.Field("lr", lr, "learning rate", config::Positive());
  }
};

struct Outer {
  int steps = 10;
  Mode mode = Mode::kFast;
  std::string name = "run";
  bool verbose = false;
  std::array<double, 3> point{0.5, 0.0, 0.2};
  Inner trainer;
  template <class V>
  void Visit(V& v) {
    v.Field("steps", steps, "optimizer steps", config::Positive());
    v.Field("mode", mode, "mode");
    v.Field("name", name, "run name");
    v.Field("verbose", verbose, "log more");
    v.Field("point", point, "a 3-D point");
    v.Field("trainer", trainer, "training");
  }
};

std::string WriteTemp(const std::string& text) {
  std::string path = (flowplan::testing::ScratchDir() / "config_test.yaml").string();
  std::ofstream(path) << text;
  return path;
}

TEST(ConfigTest, DefaultsThenFileThenOverrides) {
  const std::string path = WriteTemp("steps: 20\ntrainer:\n  lr: 0.001\n");
  const Outer c = config::Load<Outer>(path, {"trainer.dims=[8, 16, 32]", "mode=slow"});
  EXPECT_EQ(c.steps, 20);
  EXPECT_DOUBLE_EQ(c.trainer.lr, 0.001);
  EXPECT_EQ(c.trainer.dims, (std::vector<int>{8, 16, 32}));
  EXPECT_EQ(c.mode, Mode::kSlow);
  EXPECT_EQ(c.name, "run");  // untouched default
}

TEST(ConfigTest, OverrideBeatsFile) {
  const std::string path = WriteTemp("steps: 20\n");
  EXPECT_EQ(config::Load<Outer>(path, {"steps=30"}).steps, 30);
}

TEST(ConfigTest, YamlRoundTripIsExact) {
  Outer c;
  c.trainer.lr = 0.1 + 0.2;  // not representable in few digits
  c.point = {1e-300, -3.5, 7.0};
  c.name = "with: colon";
  Outer back;
  config::Apply(config::ParseYamlText(config::ToYaml(c), "round trip"), back, "round trip");
  EXPECT_EQ(back.trainer.lr, c.trainer.lr);
  EXPECT_EQ(back.point, c.point);
  EXPECT_EQ(back.name, c.name);
  EXPECT_EQ(config::ToYaml(back), config::ToYaml(c));
}

TEST(ConfigTest, JsonIsOneObjectOfEveryFieldAndReadsBackAsYaml) {
  Outer c;
  c.trainer.lr = 0.1 + 0.2;
  c.name = "say \"hi\"\n";
  c.point = {1e-300, -INFINITY, 7.0};
  EXPECT_EQ(config::ToJson(c),
            "{\"steps\": 10, \"mode\": \"fast\", \"name\": \"say \\\"hi\\\"\\n\", \"verbose\": false, "
            "\"point\": [1e-300, null, 7.0], \"trainer\": {\"dims\": [32, 64], \"lr\": 0.30000000000000004}}");
  // JSON is YAML: with finite numbers it reads back to the same config.
  c.point[1] = -3.5;
  Outer back;
  config::Apply(config::ParseYamlText(config::ToJson(c), "json"), back, "json");
  EXPECT_EQ(config::ToYaml(back), config::ToYaml(c));
}

TEST(ConfigTest, NumbersAreWrittenShortAndExact) {
  EXPECT_EQ(config::internal::FormatDouble(10.0), "10.0");
  EXPECT_EQ(config::internal::FormatDouble(2e-4), "0.0002");
  EXPECT_EQ(config::internal::FormatDouble(0.995), "0.995");
  EXPECT_EQ(config::internal::FormatDouble(1e-300), "1e-300");
  for (double x : {0.1 + 0.2, 1.0 / 3.0, 12345.678, -7.25e-9}) {
    EXPECT_EQ(std::strtod(config::internal::FormatDouble(x).c_str(), nullptr), x);
  }
}

TEST(ConfigTest, UnknownKeyNamesFileLineAndKey) {
  const std::string path = WriteTemp("steps: 20\ntrainer:\n  bach_size: 3\n");
  EXPECT_THAT([&] { config::Load<Outer>(path, {}); },
              ThrowsMessage<Error>(AllOf(HasSubstr(path + ":3"), HasSubstr("trainer.bach_size"),
                                         HasSubstr("unknown key"))));
}

TEST(ConfigTest, WrongTypeNamesKeyAndValue) {
  const std::string path = WriteTemp("steps: abc\n");
  EXPECT_THAT([&] { config::Load<Outer>(path, {}); },
              ThrowsMessage<Error>(AllOf(HasSubstr(path + ":1: steps"), HasSubstr("expected a decimal integer"),
                                         HasSubstr("\"abc\""))));
}

TEST(ConfigTest, IntegersAreDecimal) {
  // yaml-cpp alone would read 010 as octal 8 and 0x10 as 16.
  for (const char* text : {"010", "0x10", "1e3", "12abc"}) {
    EXPECT_THAT([&] { config::Load<Outer>("", {std::string("steps=") + text}); },
                ThrowsMessage<Error>(AllOf(HasSubstr("steps: expected a decimal integer"), HasSubstr(text))))
        << text;
  }
  EXPECT_EQ(config::Load<Outer>("", {"steps=+12"}).steps, 12);
}

TEST(ConfigTest, OutOfBoundsValueIsRejected) {
  EXPECT_THAT([] { config::Load<Outer>("", {"steps=0"}); },
              ThrowsMessage<Error>(AllOf(HasSubstr("command line: steps"), HasSubstr("positive"))));
  EXPECT_THAT([] { config::Load<Outer>("", {"trainer.dims=[4, -1]"}); },
              ThrowsMessage<Error>(HasSubstr("trainer.dims[1]")));
  EXPECT_THAT([] { config::Load<Outer>("", {"trainer.lr=nan"}); },
              ThrowsMessage<Error>(HasSubstr("trainer.lr")));
}

TEST(ConfigTest, EnumListsChoices) {
  EXPECT_THAT([] { config::Load<Outer>("", {"mode=medium"}); },
              ThrowsMessage<Error>(AllOf(HasSubstr("mode"), HasSubstr("one of fast, slow"),
                                         HasSubstr("\"medium\""))));
}

TEST(ConfigTest, FixedSizeListNeedsExactLength) {
  EXPECT_THAT([] { config::Load<Outer>("", {"point=[1, 2]"}); },
              ThrowsMessage<Error>(AllOf(HasSubstr("point"), HasSubstr("list of 3 values"))));
}

TEST(ConfigTest, MalformedOverrideAndMissingFile) {
  EXPECT_THAT([] { config::Load<Outer>("", {"steps"}); },
              ThrowsMessage<Error>(HasSubstr("key.sub=value")));
  EXPECT_THAT([] { config::Load<Outer>("/nonexistent/x.yaml", {}); },
              ThrowsMessage<Error>(HasSubstr("/nonexistent/x.yaml")));
  const std::string path = WriteTemp("steps: [1\n");
  EXPECT_THAT([&] { config::Load<Outer>(path, {}); },
              ThrowsMessage<Error>(AllOf(HasSubstr(path), HasSubstr("not valid YAML"))));
}

TEST(ConfigTest, KeyGivenTwiceIsAnErrorNotTheFirstValue) {
  const std::string path = WriteTemp("steps: 5\ntrainer:\n  lr: 0.1\nsteps: 7\n");
  EXPECT_THAT([&] { config::Load<Outer>(path, {}); },
              ThrowsMessage<Error>(AllOf(HasSubstr(path + ":4"), HasSubstr("steps: key given twice"))));
  const std::string nested = WriteTemp("trainer:\n  lr: 0.1\n  lr: 0.2\n");
  EXPECT_THAT([&] { config::Load<Outer>(nested, {}); },
              ThrowsMessage<Error>(AllOf(HasSubstr(nested + ":3"), HasSubstr("trainer.lr: key given twice"))));
}

TEST(ConfigTest, AFolderIsNotAConfigFile) {
  const std::string folder = flowplan::testing::ScratchDir().string();
  EXPECT_THAT([&] { config::Load<Outer>(folder, {}); },
              ThrowsMessage<Error>(AllOf(HasSubstr(folder), HasSubstr("is a folder"))));
}

TEST(ConfigTest, EmptyFileKeepsDefaults) {
  const std::string path = WriteTemp("");
  EXPECT_EQ(config::Load<Outer>(path, {}).steps, 10);
}

TEST(ConfigTest, KeyListingShowsEveryLeafWithDefault) {
  const auto keys = config::ListKeys(Outer{});
  ASSERT_EQ(keys.size(), 7u);
  EXPECT_EQ(keys[0].key, "steps");
  EXPECT_EQ(keys[0].default_value, "10");
  EXPECT_EQ(keys[5].key, "trainer.dims");
  EXPECT_EQ(keys[5].default_value, "[32, 64]");
  EXPECT_THAT(keys[1].help, HasSubstr("fast, slow"));
}

}  // namespace
}  // namespace flowplan

TEST(ErrorTest, AMessageQuotingControlCharactersStaysOneLine) {
  // What fuzzing found: a bad value holding a newline (or a YAML parser's message about one) made a two-line error.
  const flowplan::Error error(std::string("file.yaml:3: expected a number, got \"a\nb\tc\r") + '\0' + "\x01\"");
  EXPECT_EQ(std::string(error.what()), "file.yaml:3: expected a number, got \"a\\nb\\tc\\r\\x00\\x01\"");
  // Printable text, UTF-8 included, is left as it is.
  EXPECT_EQ(std::string(flowplan::Error("joint 4 is −0.07 past its limit").what()), "joint 4 is −0.07 past its limit");
}

struct MarginSection {
  double margin = 0.0;
  template <class V>
  void Visit(V& v) {
    v.Field("margin", margin, "m");
  }
};

TEST(ErrorTest, AnUnknownKeyHoldingANewlineIsNamedOnOneLine) {
  // What the config fuzz target found first (fuzz/corpus/config holds its input), as a test of its own.
  MarginSection section;
  try {
    flowplan::config::Apply(flowplan::config::ParseYamlText("\"mar\\ngin\": 1\n", "fuzz.yaml"), section, "fuzz.yaml");
    FAIL() << "an unknown key was accepted";
  } catch (const flowplan::Error& error) {
    const std::string message = error.what();
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    EXPECT_NE(message.find("unknown key"), std::string::npos) << message;
  }
}

