#include "core/interrupt.h"

#include <csignal>
#include <cstdlib>

#include "core/error.h"

namespace flowplan {
namespace {

volatile std::sig_atomic_t g_interrupted = 0;

extern "C" void OnSignal(int signal) {
  if (g_interrupted) std::_Exit(128 + signal);
  g_interrupted = 1;
}

}  // namespace

void InstallInterruptHandler() {
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
}

bool InterruptRequested() { return g_interrupted != 0; }

void ClearInterrupt() { g_interrupted = 0; }

void ThrowIfInterrupted() {
  if (g_interrupted) throw Error("interrupted");
}

}  // namespace flowplan
