#include "interrupts.h"

#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstring>

#include "tool_error.h"

namespace attitude_propagator {
namespace tools {

namespace {

// The first signal only sets g_signal: the run stops at its next check and unwinds, which
// removes the partial files. A second one (the user insists, or the run is stuck in a long
// system call) removes them here and exits at once. The handler reads only lock-free atomics
// and fixed arrays and calls only unlink() and _exit(), which are async-signal-safe.
std::atomic<int> g_signal{0};
constexpr int kPendingSlots = 4;
constexpr std::size_t kPendingPath = 4096;
std::atomic<bool> g_pending_used[kPendingSlots];
char g_pending_path[kPendingSlots][kPendingPath];

extern "C" void onSignal(int signal) {
  int none = 0;
  if (g_signal.compare_exchange_strong(none, signal)) return;
  for (int i = 0; i < kPendingSlots; ++i) {
    if (g_pending_used[i].load()) ::unlink(g_pending_path[i]);
  }
  ::_exit(128 + signal);
}

}  // namespace

int registerPending(const std::string& path) {
  if (path.size() >= kPendingPath) return -1;
  for (int i = 0; i < kPendingSlots; ++i) {
    if (g_pending_used[i].load()) continue;
    std::memcpy(g_pending_path[i], path.c_str(), path.size() + 1);
    g_pending_used[i].store(true);  // after the name is complete
    return i;
  }
  return -1;
}

void unregisterPending(int slot) {
  if (slot >= 0) g_pending_used[slot].store(false);
}

void catchInterrupts() {
  struct sigaction action {};
  action.sa_handler = onSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;
  for (int signal : {SIGINT, SIGTERM, SIGHUP}) ::sigaction(signal, &action, nullptr);
  std::signal(SIGXFSZ, SIG_IGN);
}

void throwIfInterrupted() {
  if (const int signal = g_signal.load()) {
    throw ToolError(std::string("interrupted (") + ::strsignal(signal) + "): no output written",
                    128 + signal);
  }
}

}  // namespace tools
}  // namespace attitude_propagator
