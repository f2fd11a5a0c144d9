"""One palette for every picture lanekeep makes (the recording, the PNG plots): each source's
colour by name, mid-tones readable on light and dark backgrounds."""

from __future__ import annotations

from lanekeep.scoring.step_score import FUSED, REFERENCE

TRUTH, OUTPUT = "truth", "output"
ROAD_COLOUR, PATH_COLOUR, CAR_COLOUR = (128, 128, 128), (140, 80, 30), (60, 60, 200)
VEHICLE_COLOUR = (230, 120, 0)  # the other vehicles' footprints and boxes


# Mid-tone colours, each readable on the viewer's light and dark themes (no white, no black);
# the fused output gets the strongest one.
COLOURS = {
    TRUTH: (30, 170, 30),
    OUTPUT: (220, 20, 20),
    FUSED: (220, 20, 20),
    REFERENCE: (120, 90, 230),
    "hough": (255, 140, 0),
    "sliding_window": (0, 140, 230),
    "lanenet": (190, 50, 190),
}


SPARE_COLOURS = ((200, 150, 0), (0, 160, 150), (150, 110, 60), (230, 90, 140))


def colour(name: str, index: int = 0) -> tuple[int, int, int]:
    """Fixed colour per source, so a model has the same colour in every view."""
    return COLOURS.get(name, SPARE_COLOURS[index % len(SPARE_COLOURS)])


def matplotlib_colour(name: str, index: int = 0) -> tuple[float, float, float]:
    """`colour` as matplotlib takes it (RGB in 0..1), for the PNG plots of runs and sweeps
    alike; a model's own track (`hough:track`) shares its model's colour (drawn dashed)."""
    r, g, b = colour(name.removesuffix(":track"), index)
    return r / 255, g / 255, b / 255
