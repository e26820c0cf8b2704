#pragma once
// The 4-node bilinear quad on a (possibly warped) surface in 3D: shape functions, the
// covariant surface metric and the 2x2 Gauss rule. Device-callable math on small arrays.
#include <Kokkos_Core.hpp>

namespace perishell::mesh::bilinear {

// Natural coordinates of the nodes, counter-clockwise.
KOKKOS_INLINE_FUNCTION constexpr double nodeXi(int a) { return (a == 1 || a == 2) ? 1.0 : -1.0; }
KOKKOS_INLINE_FUNCTION constexpr double nodeEta(int a) { return (a >= 2) ? 1.0 : -1.0; }

// 2x2 Gauss points at +-1/sqrt(3), weight 1: exact for the bilinear quad's area and
// stiffness integrands on flat elements.
constexpr int numGaussPoints = 4;
KOKKOS_INLINE_FUNCTION constexpr double gaussXi(int q) { return 0.57735026918962576451 * nodeXi(q); }
KOKKOS_INLINE_FUNCTION constexpr double gaussEta(int q) { return 0.57735026918962576451 * nodeEta(q); }

// Everything a surface integrand needs at one point: N_a, dN_a/dxi, dN_a/deta, the metric
// g_ab = dx/dxi_a . dx/dxi_b and the area element |g_1 x g_2|.
struct SurfacePoint {
  double shape[4];
  double dShapeDxi[4];
  double dShapeDeta[4];
  double g11, g12, g22;
  double areaElement;

  // Surface gradient inner product grad(N_a) . grad(N_b) = [N_a,xi N_a,eta] G^-1 [N_b,xi N_b,eta]^T.
  KOKKOS_INLINE_FUNCTION double gradientDot(int a, int b) const {
    const double det = g11 * g22 - g12 * g12;
    return (dShapeDxi[a] * (g22 * dShapeDxi[b] - g12 * dShapeDeta[b]) +
            dShapeDeta[a] * (g11 * dShapeDeta[b] - g12 * dShapeDxi[b])) / det;
  }
};

KOKKOS_INLINE_FUNCTION SurfacePoint evaluate(const double x[4][3], double xi, double eta) {
  SurfacePoint p{};
  double g1[3] = {0.0, 0.0, 0.0};
  double g2[3] = {0.0, 0.0, 0.0};
  for (int a = 0; a < 4; ++a) {
    p.shape[a] = 0.25 * (1.0 + nodeXi(a) * xi) * (1.0 + nodeEta(a) * eta);
    p.dShapeDxi[a] = 0.25 * nodeXi(a) * (1.0 + nodeEta(a) * eta);
    p.dShapeDeta[a] = 0.25 * nodeEta(a) * (1.0 + nodeXi(a) * xi);
    for (int k = 0; k < 3; ++k) {
      g1[k] += p.dShapeDxi[a] * x[a][k];
      g2[k] += p.dShapeDeta[a] * x[a][k];
    }
  }
  p.g11 = g1[0] * g1[0] + g1[1] * g1[1] + g1[2] * g1[2];
  p.g12 = g1[0] * g2[0] + g1[1] * g2[1] + g1[2] * g2[2];
  p.g22 = g2[0] * g2[0] + g2[1] * g2[1] + g2[2] * g2[2];
  const double n0 = g1[1] * g2[2] - g1[2] * g2[1];
  const double n1 = g1[2] * g2[0] - g1[0] * g2[2];
  const double n2 = g1[0] * g2[1] - g1[1] * g2[0];
  p.areaElement = Kokkos::Experimental::sqrt(n0 * n0 + n1 * n1 + n2 * n2);
  return p;
}

template <class CoordinatesT, class QuadsT>
KOKKOS_INLINE_FUNCTION void gatherNodes(const CoordinatesT& coordinates, const QuadsT& quads,
                                        int element, double x[4][3]) {
  for (int a = 0; a < 4; ++a)
    for (int k = 0; k < 3; ++k) x[a][k] = coordinates(quads(element, a), k);
}

}  // namespace perishell::mesh::bilinear
