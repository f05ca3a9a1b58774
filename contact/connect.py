"""``connect``: the contact element for two contours, by their kinds.

A point or a sphere against a surface is a :class:`~contact.contact.Contact` with the
kinematics registered for the pair (:data:`contact.PAIR_KINEMATICS`); for a
:class:`~contact.laws.Bilateral` law a :class:`~contact.contact.CurveConstraint`
(:data:`contact.BILATERAL_KINEMATICS`); a face — a neutral 1s or 2s contour of a flexible
body — against a surface a :class:`~contact.face.FaceContact`, a point contact at each of
the face's nodes.
"""

from __future__ import annotations

from contours.neutral.factory import NeutralContour
from contours.registry import CONTOURS

from .contact import Contact, CurveConstraint
from .face import FaceContact
from .laws import Bilateral
from .registry import BILATERAL_KINEMATICS, PAIR_KINEMATICS, make_law


def connect(contour1, contour2, law, friction=None, name="contact", margin="auto"):
    """The contact between ``contour1`` and ``contour2`` (module docstring; contour kinds:
    :data:`contours.CONTOURS`). ``law`` is a law or a name of :data:`contact.LAWS` (its
    default parameters); ``friction``, ``margin`` [m] as for :class:`~contact.contact.Contact`."""
    law = make_law(law) if isinstance(law, str) else law
    if isinstance(contour1, NeutralContour) and not isinstance(law, Bilateral):
        return FaceContact(contour1, contour2, law, friction=friction, name=name, margin=margin)
    kinds = (CONTOURS.name_of(contour1), CONTOURS.name_of(contour2))
    if isinstance(law, Bilateral):
        return CurveConstraint(BILATERAL_KINEMATICS[kinds](contour1, contour2), name=name)
    return Contact(PAIR_KINEMATICS[kinds](contour1, contour2), law, friction=friction, name=name, margin=margin)
