"""Volume-rendering quadrature (the standard NeRF form that paper Eq. 1 means).

For samples i with density sigma_i and interval length delta_i:

    alpha_i = 1 - exp(-sigma_i delta_i)
    T_i     = exp(-sum_{j<i} sigma_j delta_j)      (exclusive running sum, kept in log space)
    w_i     = T_i alpha_i                            and  C = sum_i w_i c_i.

Keeping the optical depth sum_{j<i} sigma_j delta_j instead of the product of transmittances avoids
underflow chains, alpha uses a cancellation-free 1 - exp(-x) and T an exp accurate for every argument
(:mod:`mi_voldis.field.activations`, on CUDA's approximate exp too), so densities from 1e-8 to 1e8 give alpha
in [0, 1] with full relative precision. ``ops``: as in :mod:`mi_voldis.field.activations`.
"""
import math

from ..field.activations import DRJIT, exp, one_minus_exp

# Rays stop once every field's transmittance is below this (early termination): what is left can change
# a pixel by at most that much (times its colour). The ``voldis`` integrator's ``stop_transmittance``.
STOP_TRANSMITTANCE = 1e-4


def stop_depth(stop_transmittance):
    """The optical depth -ln T at which a ray's transmittance falls to ``stop_transmittance``."""
    return float(-math.log(stop_transmittance))


def alpha(optical_depth, ops=DRJIT):
    """Opacity of one interval, alpha = 1 - exp(-sigma delta)."""
    return one_minus_exp(optical_depth, ops)


def transmittance(optical_depth_before, ops=DRJIT):
    """T_i = exp(-sum_{j<i} sigma_j delta_j)."""
    return exp(-optical_depth_before, ops)


def weight(optical_depth_before, optical_depth, ops=DRJIT):
    """w_i = T_i alpha_i."""
    return transmittance(optical_depth_before, ops) * alpha(optical_depth, ops)
