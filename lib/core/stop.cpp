#include "core/stop.h"

#include <atomic>
#include <csignal>
#include <string>

#include "core/error.h"

namespace rs {

namespace {
std::atomic<int> requested{0};
static_assert(std::atomic<int>::is_always_lock_free, "set from a signal handler");
}  // namespace

void requestStop(int signal) {
    int none = 0;
    requested.compare_exchange_strong(none, signal > 0 ? signal : SIGINT);
}

int stopSignal() { return requested.load(std::memory_order_relaxed); }

void throwIfStopped() {
    const int s = stopSignal();
    if (s == 0) return;
    const std::string name = s == SIGINT ? "SIGINT" : s == SIGTERM ? "SIGTERM" : "signal " + std::to_string(s);
    throw Error(ErrorKind::Interrupted, "interrupted by " + name);
}

}  // namespace rs
