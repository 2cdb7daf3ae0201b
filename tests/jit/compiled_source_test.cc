// jit::CompiledSource: a flowplan.script file as TorchScript compiles it (imports blanked, a class file's methods
// taken out of the class, line numbers kept), and a class file and a user's text compiled through it.

#include <gtest/gtest.h>

#include <algorithm>

#include "jit/library.h"

namespace flowplan::jit {
namespace {

int Lines(const std::string& text) { return static_cast<int>(std::count(text.begin(), text.end(), '\n')); }

TEST(CompiledSourceTest, ImportsAreBlankedInEveryFormAndLinesKept) {
  const std::string text =
      "# a comment\n"
      "from typing import Dict, Tuple\n"
      "import torch\n"
      "from flowplan.script.geometry.frames import (  # a comment with a ) in it\n"
      "    a, b,\n"
      "    c,\n"
      ")\n"
      "from x import y, \\\n"
      "    z\n"
      "\n"
      "def f(x: Tensor) -> Tensor:\n"
      "    return x\n";
  const std::string out = CompiledSource(text);
  EXPECT_EQ(Lines(out), Lines(text));
  EXPECT_EQ(out,
            "# a comment\n\n\n\n\n\n\n\n\n\n"
            "def f(x: Tensor) -> Tensor:\n"
            "    return x\n");
}

TEST(CompiledSourceTest, AClassBodyIsDedentedUntilModuleLevelAndStringsAreLeftAlone) {
  const std::string text =
      "import torch\n"
      "\n"
      "class Cost:\n"
      "    def value(self, x: Tensor) -> Tensor:\n"
      "        \"\"\"A docstring whose lines\n"
      "from here on\n"
      "import nothing\n"
      "class neither\"\"\"\n"
      "# a comment at the left margin\n"
      "        return x\n"
      "\n"
      "    def twice(self, x: Tensor) -> Tensor:\n"
      "        return 2 * x\n"
      "\n"
      "def after(x: Tensor) -> Tensor:\n"
      "    return x\n";
  EXPECT_EQ(CompiledSource(text),
            "\n"
            "\n"
            "\n"
            "def value(self, x: Tensor) -> Tensor:\n"
            "    \"\"\"A docstring whose lines\n"
            "from here on\n"
            "import nothing\n"
            "class neither\"\"\"\n"
            "# a comment at the left margin\n"
            "    return x\n"
            "\n"
            "def twice(self, x: Tensor) -> Tensor:\n"
            "    return 2 * x\n"
            "\n"
            "def after(x: Tensor) -> Tensor:\n"
            "    return x\n");
}

TEST(CompiledSourceTest, AClassFileCompilesOntoAModuleAndErrorsKeepTheFilesLineNumbers) {
  const std::string cost =
      "from typing import Dict\n"
      "import torch\n"
      "from torch import Tensor\n"
      "\n"
      "\n"
      "class Twice:\n"
      "    def twice(self, x: Tensor) -> Tensor:\n"
      "        return 2.0 * x\n";
  torch::jit::Module module = ModuleBuilder("Twice").MethodsFromText(cost, "twice.py").Build();
  EXPECT_TRUE(torch::equal(Call(module, "twice", {torch::ones({2})}).toTensor(), torch::full({2}, 2.0)));
  const std::string broken =
      "import torch\n"
      "\n"
      "class Broken:\n"
      "    def f(self, x: Tensor) -> Tensor:\n"
      "        return undefined_name(x)\n";
  try {
    ModuleBuilder("Broken").MethodsFromText(broken, "broken.py").Build();
    FAIL() << "compiled";
  } catch (const std::exception& e) {
    // One line naming the file, the name and the file's own line.
    EXPECT_EQ(std::string(e.what()), "broken.py: does not compile as TorchScript: undefined value undefined_name, line 5");
  }
}

}  // namespace
}  // namespace flowplan::jit
