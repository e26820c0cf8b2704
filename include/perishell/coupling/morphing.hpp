#pragma once
// The morphing coupling of PD bonds and CCM shell elements (model.md §4; paper eq. 19-23;
// Lubineau, Azdoud, Han, Rey & Askari 2012), given the nodal field alpha
// (coupling/alpha_field.hpp):
//  - every bond's micromoduli are multiplied by m_ij = (alpha_i + alpha_j)/2 (eq. 23's
//    factor), through both columns of PdBody::stiffnessScale;
//  - the CCM constitutive matrix becomes D_Hb = D - (t/2) Int m T^T D_PD T (eq. 22-23).
//
// The discrete D_Hb. Eq. 22 is the continuum statement that, under any homogeneous
// membrane strain or curvature, the bonds of node i store the fraction
//   alphaBar_i = [sum_j w_ij m_ij] / [sum_j w_ij]
// of the classical energy density (w_ij: the bond's share of the node's quadrature), so
// the CCM must store the rest: (t/2) Int m T^T D_PD T = alphaBar D in the membrane and
// bending blocks, and D_Hb = (1 - alphaBar) D there. Written with the discrete bonds, the
// weights are exactly the ones computeStiffnessScales (pd/make_body.hpp) normalised to
// the plate energy: w_ij = V_j beta_ij xi_ij s_ij (s_ij: column 0 of the stiffness scale,
// the factor on c_ax, c_by, c_tor, which carry all of the bending energy and most of the
// membrane energy). The body's PD energy is then sum_i V_i alphaBar_i W_classical, and the
// shell's, with D_Hb = (1 - alphaBar(x)) D at each Gauss point and alphaBar(x) the
// bilinear interpolation of the nodal alphaBar, is W_classical sum_a (1 - alphaBar_a)
// Int N_a dA (2x2 Gauss integrates it exactly): the sum is the classical energy wherever
// Int N_a dA is the node area A_a (parallelogram elements; otherwise to the mesh's
// distortion). Weighting by the bonds' own quadrature also absorbs the free-surface boost
// the quadrature gives to nodes at the outer edge of the transition (their missing
// neighbours, on the CCM side, count as free surface): the boost raises both the bonds'
// energy and alphaBar's denominator alike.
//
// Pure PD elements are those with alphaBar = 1 at all four nodes: nodes of PD elements
// within one horizon of the transition bond to nodes with alpha < 1 and carry alphaBar < 1,
// so the elements there keep a (small) CCM share. Transverse shear and drilling are not
// scaled (bonds carry neither; see shell/mitc4_shell.hpp).
#include <perishell/mesh/bilinear_quad.hpp>
#include <perishell/pd/pd_body.hpp>

namespace perishell::coupling {

// alphaBar per body node (bond-weighted mean of m_ij, see above), then every half bond's
// stiffness scales times m_ij. bodyAlpha: alpha of the body's nodes. A node without bonds
// gets alphaBar = alpha.
template <class ExecutionSpaceT, class MemorySpaceT>
VectorView<MemorySpaceT> morphBonds(const ExecutionSpaceT& space, pd::PdBody<MemorySpaceT>& body,
                                    const VectorView<MemorySpaceT>& bodyAlpha) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  VectorView<MemorySpaceT> alphaBar("coupling alpha bar", body.numNodes());
  const auto bonds = body.bonds;
  const auto volumes = body.volumes;
  const auto scale = body.stiffnessScale;
  Kokkos::parallel_for(
      "perishell::coupling::morphBonds::alphaBar", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, body.numNodes()),
      KOKKOS_LAMBDA(const LocalIndex node) {
        double weighted = 0.0, total = 0.0;
        for (RowOffset entry = bonds.offsets(node); entry < bonds.offsets(node + 1); ++entry) {
          const LocalIndex neighbour = bonds.neighbours(entry);
          const RowOffset b = bonds.fullToHalf(entry);
          const double w = volumes(neighbour) * bonds.volumeFactor(b) * bonds.referenceLength(b) * scale(b, 0);
          weighted += w * 0.5 * (bodyAlpha(node) + bodyAlpha(neighbour));
          total += w;
        }
        alphaBar(node) = total > 0.0 ? weighted / total : bodyAlpha(node);
      });
  Kokkos::parallel_for(
      "perishell::coupling::morphBonds::scale", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, bonds.numBonds()),
      KOKKOS_LAMBDA(const RowOffset b) {
        const double m = 0.5 * (bodyAlpha(bonds.halfBonds(b, 0)) + bodyAlpha(bonds.halfBonds(b, 1)));
        scale(b, 0) *= m;
        scale(b, 1) *= m;
      });
  return alphaBar;
}

// Per element of `quads` and Gauss point (mesh::bilinear order), the factor 1 - alphaBar(x)
// on the membrane and bending blocks of D (D_Hb above); alphaBar(x) interpolates the
// nodal nodeAlphaBar (every mesh node; 0 off the PD body).
template <class ExecutionSpaceT, class MemorySpaceT>
Kokkos::View<double* [4], Kokkos::LayoutRight, MemorySpaceT> hybridSectionScales(
    const ExecutionSpaceT& space, const QuadConnectivityView<MemorySpaceT>& quads,
    const VectorView<MemorySpaceT>& nodeAlphaBar) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  Kokkos::View<double* [4], Kokkos::LayoutRight, MemorySpaceT> scales("coupling hybrid section scale",
                                                                      quads.extent(0));
  Kokkos::parallel_for(
      "perishell::coupling::hybridSectionScales", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, quads.extent(0)),
      KOKKOS_LAMBDA(const LocalIndex e) {
        for (int q = 0; q < mesh::bilinear::numGaussPoints; ++q) {
          double interpolated = 0.0;
          for (int a = 0; a < 4; ++a) {
            const double shape = 0.25 * (1.0 + mesh::bilinear::nodeXi(a) * mesh::bilinear::gaussXi(q)) *
                                 (1.0 + mesh::bilinear::nodeEta(a) * mesh::bilinear::gaussEta(q));
            interpolated += shape * nodeAlphaBar(quads(e, a));
          }
          scales(e, q) = 1.0 - interpolated;
        }
      });
  return scales;
}

}  // namespace perishell::coupling
