// Stopping a render early. Whoever runs the library (the CLI, on SIGINT or SIGTERM) asks for a
// stop with requestStop(), which is async-signal-safe; the thread pool checks between chunks,
// and the stages' own long loops between their steps, and end the render with
// Error(Interrupted). Outputs are staged (core/staged_files.h), so none is left behind.
#pragma once

namespace rs {

void requestStop(int signal);  // async-signal-safe; the first request's signal is kept
int stopSignal();              // the requested signal, 0 when none
void throwIfStopped();         // Error(Interrupted) naming the signal, when one was requested

}  // namespace rs
