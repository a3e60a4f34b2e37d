"""The solids' energy of eq. 12 in UFL, as the exact-contact references write it: Neo-Hooke
(K, G) in plane strain with 3D invariants, no heat."""
import ufl


def pad(g):
    """A 2D gradient as a 3x3 one (plane strain)."""
    return ufl.as_matrix([[g[0, 0], g[0, 1], 0], [g[1, 0], g[1, 1], 0], [0, 0, 0]])


def first_piola(u, K, G):
    """P = dΨ/dF of eq. 12 at the displacement u: Ψ = K/2 (ln J)² + G/2 (J^(-2/3) tr C - 3)."""
    F = ufl.variable(ufl.Identity(3) + pad(ufl.grad(u)))
    J = ufl.det(F)
    psi = K / 2 * ufl.ln(J) ** 2 + G / 2 * (J ** (-2.0 / 3.0) * ufl.tr(F.T * F) - 3)
    return ufl.diff(psi, F)
