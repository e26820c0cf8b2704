#include <perishell/core/stop_request.hpp>

#include <csignal>

namespace perishell {

namespace {

volatile std::sig_atomic_t requestedSignal = 0;

extern "C" void onStopSignal(int signal) {
  if (requestedSignal != 0) {
    // The second request: the default action ends the process now.
    std::signal(signal, SIG_DFL);
    std::raise(signal);
    return;
  }
  requestedSignal = signal;
}

}  // namespace

void installStopRequestHandlers() {
  requestedSignal = 0;
  std::signal(SIGINT, onStopSignal);
  std::signal(SIGTERM, onStopSignal);
}

int stopRequestSignal() { return requestedSignal; }

const char* stopSignalName(int signal) {
  switch (signal) {
    case SIGINT: return "SIGINT";
    case SIGTERM: return "SIGTERM";
    default: return "a signal";
  }
}

void requestStop(int signal) { requestedSignal = signal; }

}  // namespace perishell
