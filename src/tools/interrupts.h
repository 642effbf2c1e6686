// Ctrl-C, SIGTERM and SIGHUP stop a run cleanly: the run unwinds and removes its partial outputs;
// a second signal removes them in the handler and exits at once.
#pragma once

#include <string>

namespace attitude_propagator {
namespace tools {

/// SIGINT, SIGTERM and SIGHUP set a flag instead of killing the program, so that a partial
/// output can be removed; throwIfInterrupted() turns it into a ToolError with exit code 128 +
/// the signal. A second signal removes the partial files itself and exits at once. SIGXFSZ (a
/// file-size limit reached) is ignored: the write fails with EFBIG and is reported like a full
/// disk.
void catchInterrupts();
void throwIfInterrupted();

/// Makes `path` (a partial output, PendingFile) known to the signal handler, which removes it on
/// a second signal; returns its slot, or -1 when none is free (or the name is too long), and then
/// only its owner removes it.
int registerPending(const std::string& path);
/// Forgets the slot registerPending returned (-1: nothing).
void unregisterPending(int slot);

}  // namespace tools
}  // namespace attitude_propagator
