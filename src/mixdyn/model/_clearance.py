"""Joints with clearance: a revolute joint with a ``clearance`` is a journal in a bearing, a
translational joint with one a slider in a guide. The joint declares the clearance and the
contact's numbers; the model replaces its equations by the contact element of its name
(:func:`clearance_contacts`), whose force, columns and drawing it then has.
"""

from __future__ import annotations

from ..errors import ModelError
from ._compliant import _check_law
from ._contact_pairs import JournalBearing, SliderInGuide

#: The contact numbers of a joint with clearance, as its contact element names them.
LAW_FIELDS = (
    "young_modulus",
    "poisson",
    "restitution",
    "impact_speed",
    "contact_model",
    "mu",
    "v_stick",
)

#: The joint classes' names that take a ``clearance``: the contact element that replaces
#: such a joint, and the fields of its geometry besides the clearance.
CLEARANCE_JOINTS = {
    "Revolute": (JournalBearing, ("journal_radius",)),
    "Translational": (SliderInGuide, ("slider_length", "corner_radius")),
}


def clearance_contacts(joints) -> tuple[tuple, tuple]:
    """``(joints, contacts)``: the joints without those that have a ``clearance``, and the
    contact element of each one's name, points and numbers (a revolute joint's
    :class:`JournalBearing`, a translational joint's :class:`SliderInGuide`; called by the
    model)."""
    kept, made = [], []
    for j in joints:
        entry = CLEARANCE_JOINTS.get(type(j).__name__)
        if entry is None or j.clearance is None:
            kept.append(j)
            continue
        cls, geometry = entry
        fields = ("clearance", *geometry, *LAW_FIELDS)
        given = {f: getattr(j, f) for f in fields if getattr(j, f) is not None}
        if cls is SliderInGuide:
            given |= {"axis": j.axis, "angle": j.angle}
        made.append(cls(j.name, j.point_i, j.point_j, **given))
    return tuple(kept), tuple(made)


def check_clearance(joint, geometry: tuple[str, ...]) -> None:
    """The checks of a joint's clearance fields (its ``__check_init__``): a clearance needs
    the numbers of its ``geometry`` (a journal's radius), the material and the restitution;
    contact numbers need a clearance."""
    given = [f for f in (*geometry, *LAW_FIELDS) if getattr(joint, f) is not None]
    if joint.clearance is None:
        if given:
            raise ModelError(
                f"{', '.join(given)} describe a clearance's contact: give the joint a "
                "clearance (e.g. clearance: 0.5 mm) or leave them out",
                joint.name,
                field=given[0],
            )
        return
    for f in (*geometry, "young_modulus", "restitution"):
        if getattr(joint, f) is None:
            raise ModelError(
                f"a joint with clearance is a contact: give its {f} ("
                + ", ".join((*geometry, "young_modulus", "restitution"))
                + "; impact_speed where restitution < 1)",
                joint.name,
                field=f,
            )
    _check_law(joint, joint.name)


__all__ = ["CLEARANCE_JOINTS", "LAW_FIELDS", "check_clearance", "clearance_contacts"]
