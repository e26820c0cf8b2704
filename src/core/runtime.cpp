#include <perishell/core/config.hpp>
#include <perishell/core/runtime.hpp>
#include <perishell/core/types.hpp>

#include <ostream>

namespace perishell {

std::string versionString() { return PERISHELL_VERSION_STRING; }

void printBackendInfo(std::ostream& out) {
  out << "perishell " << versionString() << " (backend: " << PERISHELL_BACKEND_NAME << ")\n"
      << "default execution space: " << ExecutionSpace::name() << "\n"
      << "host execution space:    " << HostExecutionSpace::name()
      << " with " << HostExecutionSpace::concurrency() << " threads\n";
  Kokkos::print_configuration(out, false);
}

}  // namespace perishell
