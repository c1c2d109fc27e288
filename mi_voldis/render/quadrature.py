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

# Rays stop once every field's transmittance is below this (early termination), their last sample taking
# the light left (:func:`weight_to_stop`): what lies behind can change a pixel by at most that much (times
# its difference from that sample's colour). The ``voldis`` integrator's ``stop_transmittance``.
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


def weight_to_stop(optical_depth_before, optical_depth, last, ops=DRJIT):
    """w_i = T_i alpha_i, or T_i where ``last``: the sample after which the ray stops early (every
    field's transmittance below the stop) takes all the light left, T_i, not T_i alpha_i. Without it
    the T_{i+1} = T_i (1 - alpha_i) < stop behind the stop is lost to black: alpha ends below 1 where
    the ray met an opaque surface and every colour is darker by up to that share. With it the pixel
    holds the last sample's colour in that share (the surface the ray stopped in), sum_i w_i = 1, and
    the error is at most T_{i+1} times the difference between that colour and what lies behind. Both
    forms are T_i times a factor of sample i's own optical depth alone, so the path-replay adjoint
    (:mod:`mi_voldis.render.march`) holds as it is."""
    return transmittance(optical_depth_before, ops) * ops.select(last, 1.0, alpha(optical_depth, ops))
