"""Derivatives of the exact flow: flow Jacobians, event-time derivatives, saltation.

Between events the state ``X = (x, x', y, y')`` obeys the linear system
``X' = A X + f(t)`` with the LO block of the damped oscillator and the ball block of
a constant acceleration, so the flow Jacobian is ``expm(A tau)`` in closed form
(:func:`flow_jacobian`). An event (an impact at ``|z| = b`` or a reversal ``z' = 0``
with friction) at a state-dependent time is handled in the extended state
``(X, t)``: :func:`piece_jacobian` is the 5x5 Jacobian of "flow from ``(X_a, t_a)``
to the event, then apply the event's reset", which contains the classical saltation
matrix ``S = D_R + (f+ - D_R f-) grad g^T / (grad g . f-)`` (:func:`saltation`).
"""

from __future__ import annotations

import math

import numpy as np

from ..params import G_ACCEL

__all__ = ["flow_jacobian", "vector_field", "impact_reset_jacobian", "piece_jacobian",
           "saltation", "law_derivative"]


def flow_jacobian(osc, tau: float) -> np.ndarray:
    """Closed-form ``d X(t0 + tau) / d X(t0)`` of a free flight (4x4).

    Parameters
    ----------
    osc : vidiscover.simulation.flows.Oscillator
        The LO of the flight (mass ``m1``, damping, stiffness).
    tau : float
        Flight duration (s).
    """
    sg, wd = osc.sigma, osc.wd
    w02 = osc.k / osc.m
    e = math.exp(-sg * tau)
    cs, sn = math.cos(wd * tau), math.sin(wd * tau)
    phi = np.zeros((4, 4))
    phi[0, 0] = e * (cs + sg / wd * sn)
    phi[0, 1] = e * sn / wd
    phi[1, 0] = -e * w02 / wd * sn
    phi[1, 1] = e * (cs - sg / wd * sn)
    phi[2, 2] = phi[3, 3] = 1.0
    phi[2, 3] = tau
    return phi


def vector_field(model, t: float, X, s: int) -> np.ndarray:
    """``X'`` of a flight with relative sliding direction ``s`` (+1, -1; 0 no friction).

    Parameters
    ----------
    model : vidiscover.simulation.engine._Model
        The resolved model (masses, base motion, friction, tilt).
    """
    x, v, _, w = X
    xe = vxe = 0.0
    for om, br, bi in model._base_terms:
        sn, cs = math.sin(om * t), math.cos(om * t)
        xe += br * sn + bi * cs
        vxe += om * (br * cs - bi * sn)
    p = model.p
    F0 = model.mu * model.m2 * G_ACCEL * s
    acc = (p.c1 * (vxe - v) + p.k1 * (xe - x) + F0) / p.m1
    ab = model.gs - model.mug * s
    return np.array([v, acc, w, ab])


def law_derivative(law, speed: float) -> float:
    """``d r / d v`` of a restitution law at impact speed ``speed`` (0 where clipped)."""
    r = law(float(speed))
    if law.kind == "constant" or r <= 0.0 or r >= 1.0:
        return 0.0
    if law.kind == "linear":
        return -law.a
    return -law.a * law.p * speed ** (law.p - 1.0)


def impact_reset_jacobian(m1: float, m2: float, rho: float) -> np.ndarray:
    """``D_R``: Jacobian of Newton's impact law with momentum conservation (4x4).

    ``rho = r + r'(|u|) |u|`` is ``-d u+ / d u-`` (``u = y' - x'``).
    """
    M = m1 + m2
    d = np.eye(4)
    dvv = (m1 - m2 * rho) / M
    dvw = (m2 + m2 * rho) / M
    d[1, 1], d[1, 3] = dvv, dvw
    d[3, 1], d[3, 3] = dvv + rho, dvw - rho
    return d


def piece_jacobian(phi: np.ndarray, f_start: np.ndarray, f_minus: np.ndarray,
                   grad_g: np.ndarray, reset: np.ndarray, g_t: float = 0.0) -> np.ndarray:
    """5x5 Jacobian of ``(X_a, t_a) -> (X_b+, t_b)`` for a flight ending at an event.

    Parameters
    ----------
    phi : ndarray (4, 4)
        Flow Jacobian over the flight.
    f_start : ndarray (4,)
        Vector field at the start of the flight (its own sliding direction).
    f_minus : ndarray (4,)
        Vector field just before the event.
    grad_g : ndarray (4,)
        Gradient of the event function ``g(X) = 0``.
    reset : ndarray (4, 4)
        ``D_R``, the reset's Jacobian (identity for a reversal).
    g_t : float
        Explicit time derivative of the event function (the release of a stuck ball
        depends on the base motion).
    """
    part = np.hstack([phi, -(phi @ f_start)[:, None]])      # dX_b-/d(X_a, t_a), t_b fixed
    denom = float(grad_g @ f_minus) + g_t
    dt = -(grad_g @ part) / denom                             # d t_b / d(X_a, t_a)
    out = np.empty((5, 5))
    out[:4] = reset @ (part + np.outer(f_minus, dt))
    out[4] = dt
    return out


def saltation(reset: np.ndarray, f_minus: np.ndarray, f_plus: np.ndarray,
              grad_g: np.ndarray) -> np.ndarray:
    """The saltation matrix ``D_R + (f+ - D_R f-) grad g^T / (grad g . f-)`` (4x4)."""
    return reset + np.outer(f_plus - reset @ f_minus, grad_g) / float(grad_g @ f_minus)
