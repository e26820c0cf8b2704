// The stack-verification case compiled for Kokkos::OpenMP (pressurised_membrane.hpp).
#include <perishell/cases/pressurised_membrane.hpp>

#ifdef KOKKOS_ENABLE_OPENMP
namespace perishell::cases {
template PressurisedMembraneResult runPressurisedMembrane(const Kokkos::OpenMP&, const PressurisedMembraneOptions&);
}  // namespace perishell::cases
#endif
