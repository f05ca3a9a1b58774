"""Output probes: what the driver samples at the output times (DESIGN stage 8).

An output spec is a :class:`~mbs.bodies.body.Frame` (its inertial position) or a callable
(t, q, u) -> array on the system's state. :func:`probe` turns a spec into a callable;
a frame becomes a :class:`FramePosition`, which also writes its position into a row of
the result in place (:meth:`FramePosition.into`): on a free quaternion body (FFR or
rigid) by the kernel :func:`mbs.bodies._kernels.free_point_position_into`, r = R + A (ū0 + Φ q_f)
(thesis eq. 2.24), on a point mass as q + ū0; other frames (prescribed body frames,
other parametrizations, the ground) through :meth:`Frame.position`.
"""

from __future__ import annotations

from ffrmbs.errors import ModelError

from mbs.bodies._kernels import free_point_position_into
from mbs.bodies.body import Frame
from mbs.bodies.rigid_body import PointMass

GENERIC, FREE_QUATERNION, POINT_MASS = 0, 1, 2


class FramePosition:
    """The inertial position r (3,) [m] of ``frame`` as a probe (t, q, u) on the system's
    state (module docstring)."""

    def __init__(self, frame: Frame):
        self.frame = frame
        body = frame.body
        self.at = 0 if body is None else body.q_slice.start
        if body is None:
            self.kind = GENERIC
        elif type(body) is PointMass:
            self.kind = POINT_MASS
        elif getattr(body, "free_quaternion", False):
            self.kind = FREE_QUATERNION
        else:
            self.kind = GENERIC

    def __call__(self, t, q, u):
        """r (3,) [m], a new array."""
        f = self.frame
        return f.position(None if f.body is None else q[f.body.q_slice], t)

    def into(self, t, q, out) -> None:
        """Write r (3,) [m] at (t [s], q) into ``out``, allocating nothing for free
        quaternion bodies and point masses."""
        if self.kind == FREE_QUATERNION:
            free_point_position_into(q, self.at, self.frame.u0, self.frame.phi, out)
        elif self.kind == POINT_MASS:
            a, u0 = self.at, self.frame.u0
            out[0] = q[a] + u0[0]
            out[1] = q[a + 1] + u0[1]
            out[2] = q[a + 2] + u0[2]
        else:
            out[:] = self(t, q, None)


def probe(spec):
    """A callable (t, q, u) -> array for an output spec: a Frame (its position, a
    :class:`FramePosition`) or a callable (returned as is)."""
    if isinstance(spec, Frame):
        return FramePosition(spec)
    if callable(spec):
        return spec
    raise ModelError(f"an output must be a Frame or a callable (t, q, u), got {spec!r}")
