// The stack-verification case compiled for Kokkos::Cuda (pressurised_membrane.hpp).
#include <perishell/cases/pressurised_membrane.hpp>

#ifdef KOKKOS_ENABLE_CUDA
namespace perishell::cases {
template PressurisedMembraneResult runPressurisedMembrane(const Kokkos::Cuda&, const PressurisedMembraneOptions&);
}  // namespace perishell::cases
#endif
