#pragma once
// Build and runtime facts a user needs to trust a result: version, backend, devices.
#include <iosfwd>
#include <string>

namespace perishell {

std::string versionString();
// Human-readable report of the Kokkos configuration and the devices in use; Kokkos must be
// initialised.
void printBackendInfo(std::ostream& out);

}  // namespace perishell
