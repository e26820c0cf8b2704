// StaticNewtonSolver compiled for Kokkos::OpenMP (static_newton_impl.hpp says why here).
#include <perishell/solvers/implicit/static_newton_impl.hpp>

#ifdef KOKKOS_ENABLE_OPENMP
namespace perishell::solvers {
template class StaticNewtonSolver<Kokkos::OpenMP>;
}  // namespace perishell::solvers
#endif
