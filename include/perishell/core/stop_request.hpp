#pragma once
// SIGINT and SIGTERM as a request to stop: the first one is recorded, and a run ends after its
// current step (explicit) or increment (implicit) with that state written, its summary printed
// and exit status 128 + the signal (130, 143); a second one ends the process at once. Without
// the handlers installed (library use, tests) nothing changes.
namespace perishell {

// Installs the handlers and clears any earlier request. Call once, before a run.
void installStopRequestHandlers();

// The signal that asked the run to stop, or 0.
int stopRequestSignal();

// "SIGINT", "SIGTERM", or "a signal" for any other.
const char* stopSignalName(int signal);

// For tests: records a request as the handler would (no signal is raised).
void requestStop(int signal);

}  // namespace perishell
