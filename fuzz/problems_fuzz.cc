// A problem file (`flowplan plan --problems`, problems::LoadProblemSet).

#include "fuzz/fuzz_input.h"
#include "problems/problem.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    const flowplan::problems::ProblemSet set = flowplan::problems::LoadProblemSet(flowplan::fuzz::AsFile(data, size, ".yaml"));
    flowplan::problems::ProblemSetYaml(set);
  } catch (const flowplan::Error& error) {
    flowplan::fuzz::ExpectOneLine(error);
  }
  return 0;
}
