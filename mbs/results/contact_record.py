"""What ``Result.contacts`` records of each contact at an output sample
(``System.simulate(contacts=True)``; the result file's ``/contacts/<contact>/``).

* ``active``: closed at the last step's midpoint;
* ``gap`` [m], ``point`` [m], ``normal``: the normal gap of the contact geometry, the
  contact point on the second contour and the normal (world). While the contact is
  closed, those the last step located at its midpoint, the gap being the effective one
  g_N + δ of a contact through residual flexibility (:mod:`contact.compliance`, S1: the
  surface deflected by the spring δ as well as by the kept modes); while it is open (or
  pruned by the plan, or separated by the broad phase, when the steps do not locate it),
  located afresh at the sample's state (t, q, u), the broad phase left out: a pair kind
  with a fused detection in copies of its arrays (:class:`mbs.run.fused_detection.Probe`),
  else (and when the probe cannot start from the run's or its own last contact point) the
  contours updated and the search run there — which seeds the probe's own —, the run's
  contact state (Data's ``contact_f``, ``contact_i``) put back afterwards — either way
  recording changes nothing of the run. NaN where no contact
  point exists (a point beyond the contour's domain);
* ``deflection`` [m]: δ of the normal row, the spring's deflection at the end of the last
  step of a closed contact through residual flexibility (0 otherwise);
* ``force`` [N]: the integrator's (``Integrator.contact_force``).

A point kept on a curve (not unilateral) records what its last step located.
"""

from __future__ import annotations

import numpy as np

FIELDS = {"active": ((), np.int8, "1"), "gap": ((), float, "m"), "point": ((3,), float, "m"),
          "normal": ((3,), float, "1"), "deflection": ((), float, "m"), "force": ((3,), float, "N")}
"""Per contact: shape of one sample, dtype, units."""

DESCRIPTIONS = {
    "active": "closed at the last step's midpoint",
    "gap": "normal gap of the contact geometry [m]: while closed, at the last step's midpoint, g_N + deflection "
           "(the spring of residual flexibility included); while open, at the sample time; NaN where no contact "
           "point exists",
    "point": "contact point on the second contour (world) [m], where the gap is measured",
    "normal": "contact normal (world), where the gap is measured",
    "deflection": "spring deflection of residual flexibility along the normal at the end of the last step [m] "
                  "(0 without it or while open)",
    "force": "contact force on the first contour's body (world) [N]: the impulse of the last step / dt for "
             "set-valued laws",
}
"""Per contact field: what it is (the result file's ``description`` attributes)."""


def empty_records(contacts, n) -> dict:
    """{contact name: {field: (n, ...) array}} of ``n`` samples (NaN, zero flags and forces)."""
    return {c.name: {key: (np.zeros((n,) + shape, dtype=dtype) if key in ("active", "force", "deflection")
                           else np.full((n,) + shape, np.nan))
                     for key, (shape, dtype, unit) in FIELDS.items()} for c in contacts}


class ContactRecorder:
    """Samples the contacts of a compiled run into ``Result.contacts`` (module docstring).

    Parameters
    ----------
    model : mbs.run.model.Model
        The run's Model: its contacts and the (q, u) slices of their contours.
    """

    def __init__(self, model):
        self.model = model
        self.slices = {id(contour): (qs, us) for contour, owners, qs, us in model.contours}
        self.probes = [None if f is None else f.probe() for f in model.fused]
        self._kept = None       # copies of Data's contact_f, contact_i while a contact is located afresh

    def record(self, data, records, i, t, q, u) -> None:
        """Sample ``i`` of every contact (but the force) into ``records`` at the state
        (t [s], q, u) of the whole system."""
        model = self.model
        kept = False            # the run's contact state saved before the first fresh locate
        for j, c in enumerate(model.contacts):
            rec, k = records[c.name], c.kinematics
            closed = bool(data.closed[j])
            rec["active"][i] = closed
            rec["deflection"][i] = delta = self.deflection(data, j) if closed else 0.0
            afresh = c.unilateral and not closed
            found = self.probes[j].locate(q, u) if afresh and self.probes[j] is not None else None
            if found is not None:
                gap, point, normal = found
                rec["gap"][i], rec["point"][i], rec["normal"][i] = gap + delta, point, normal
                continue
            if afresh and not kept:
                self.keep(data)
                kept = True
            located = self.locate(c, t, q, u) if afresh else k.active
            rec["gap"][i] = k.g_N + delta if located else np.nan
            rec["point"][i] = k.point2.r if located else np.nan
            rec["normal"][i] = k.n if located else np.nan
            if afresh and located and self.probes[j] is not None:
                self.probes[j].seed()               # its warm start while the run has none
        if kept:
            self.put_back(data)

    def deflection(self, data, j) -> float:
        """δ [m] of contact ``j``'s normal row at the end of the last step (0 without
        residual flexibility or without a spring state)."""
        model = self.model
        if model.residual is None or not model.residual.compliant[j] or not data.warm[j]:
            return 0.0
        return float(data.comp_delta[model.lam_at[j]])

    def keep(self, data) -> None:
        """The run's contact state (``data.contact_f``, ``contact_i``) kept for
        :meth:`put_back` (in buffers made on the first sample), before contacts are
        located afresh: once per sample, all of them located at the same (t, q, u)."""
        if self._kept is None:
            self._kept = (data.contact_f.copy(), data.contact_i.copy())
        else:
            np.copyto(self._kept[0], data.contact_f)
            np.copyto(self._kept[1], data.contact_i)

    def locate(self, contact, t, q, u) -> bool:
        """Locate ``contact`` at (t, q, u) without the broad phase, its contours updated
        there (after :meth:`keep`). True if a contact point exists (the kinematics then
        hold g_N, the point and the normal)."""
        k = contact.kinematics
        for contour in (k.contour1, k.contour2):
            qs, us = self.slices[id(contour)]
            if qs is None:
                contour.update(None, None, t)
            else:
                contour.update(q[qs], u[us], t)
        return bool(k.update(velocity=False, jacobians=False))

    def put_back(self, data) -> None:
        """The run's contact state :meth:`locate` kept, put back into ``data``."""
        np.copyto(data.contact_f, self._kept[0])
        np.copyto(data.contact_i, self._kept[1])
