"""The pavement keys of a scenario's `[road]` table: how the carriageway is surfaced (the
texture that shows it is drawn by lanekeep/world/pavement.py)."""

from __future__ import annotations

from dataclasses import dataclass

from lanekeep.core.setting import check_settings, setting

SURFACES = ("asphalt", "concrete")
SECTION_SURFACES = ("repaved", "asphalt", "concrete")


@dataclass(frozen=True)
class PavementStyle:
    """How the carriageway is surfaced. Densities are 0 (none) .. 1 (a road overdue for repair).
    A scenario holds these keys in `[road]` (lanekeep/scenario/road.py `RoadConfig`, whose
    fields are these). The structure keys after `tyre_marks` (tar lines, seams, the oil stripe,
    sections of another surface) are off by default: what real roads show and a lane detector
    may take for a line."""

    surface: str = setting("asphalt", "Pavement material (concrete: light grey slabs with "
                           "joints).", choices=SURFACES)
    asphalt_tone: float = setting(0.5, "0 fresh black .. 1 old, sun-bleached grey.",
                                  bounds=(0.0, 1.0))
    cracks: float = setting(0.3, "Amount of cracks in the pavement.", bounds=(0.0, 1.0))
    patches: float = setting(0.2, "Amount of repair patches.", bounds=(0.0, 1.0))
    tyre_marks: float = setting(0.4, "Darker wheel paths and oil strip in every lane.",
                                bounds=(0.0, 1.0))
    tar_lines: float = setting(0.0, "Amount of crack sealant: long dark meandering tar lines, "
                               "mostly along the road, some across it.", bounds=(0.0, 1.0))
    seams: float = setting(0.0, "Strength of the longitudinal construction seam a little "
                           "inside each lane's left line (where two paving passes met; the "
                           "strip beyond it a slightly other shade); 0 = none.",
                           bounds=(0.0, 1.0))
    oil_stripe: float = setting(0.0, "Darkness of the oil-dripped stripe down each lane's "
                                "centre, with the wheel paths beside it polished lighter; "
                                "0 = none.", bounds=(0.0, 1.0))
    surface_changes: float = setting(0.0, "Share of the road's length (in sections of 25-120 "
                                     "m with straight transverse ends) surfaced with "
                                     "`section_surface` instead; 0 = none.", bounds=(0.0, 0.9))
    section_surface: str = setting("repaved", "What those sections are: repaved (newer, "
                                   "darker asphalt), asphalt or concrete.",
                                   choices=SECTION_SURFACES)

    def __post_init__(self):
        check_settings(self)
