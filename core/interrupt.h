#pragma once

namespace flowplan {

/// Installs SIGINT/SIGTERM handlers that only raise a flag; long loops poll
/// ThrowIfInterrupted() so that temporaries are cleaned up by their destructors.
/// A second signal exits at once.
void InstallInterruptHandler();

bool InterruptRequested();

/// Lowers the flag again: for a process that goes on after an interrupted run (a Python session).
void ClearInterrupt();

/// @throws flowplan::Error("interrupted") once a signal has arrived.
void ThrowIfInterrupted();

}  // namespace flowplan
