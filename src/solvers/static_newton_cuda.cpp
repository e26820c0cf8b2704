// StaticNewtonSolver compiled for Kokkos::Cuda (static_newton_impl.hpp says why here).
#include <perishell/solvers/implicit/static_newton_impl.hpp>

#ifdef KOKKOS_ENABLE_CUDA
namespace perishell::solvers {
template class StaticNewtonSolver<Kokkos::Cuda>;
}  // namespace perishell::solvers
#endif
