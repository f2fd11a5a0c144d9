"""The rerun viewer's layout for an episode (which panels, where) and the scenario's Markdown
card shown beside them."""

from __future__ import annotations

import math
from pathlib import Path

from lanekeep.detectors.registry import front_labels
from lanekeep.report.palette import FUSED, REFERENCE, TRUTH

# -- the blueprint ------------------------------------------------------------------------------
TIMELINE = "sim_time"  # the default timeline: simulated seconds (the recording also has `step`)
KEY_ORIGIN = "key"  # the colour key (record.py logs it): one key instead of a legend per plot


def _plot(origin: str, name: str, **kwargs):
    """A time-series panel without its legend: legends are drawn over the plot (they hid the
    first fifth of every curve); the colours are the same in every panel and the key says
    which is which."""
    import rerun.blueprint as rrb

    return rrb.TimeSeriesView(origin=origin, name=name,
                              plot_legend=rrb.PlotLegend(visible=False), **kwargs)


def has_other_vehicles(scenario) -> bool:
    """Whether the scenario puts other vehicles on the road (listed ones, drawn traffic or a
    scripted event's): then the layout shows the safety plots."""
    traffic = scenario.traffic
    return bool(scenario.conditions.vehicles or traffic.vehicles_per_km > 0
                or any(getattr(traffic, "lane_vehicles_per_km", ()))
                or getattr(traffic, "events", ()))


def _safety_column(scenario):
    """Gap and time to collision to the vehicle ahead, the car's acceleration (one unit a
    plot; lanekeep/scoring/safety.py)."""
    import rerun.blueprint as rrb

    return rrb.Vertical(
        _plot("plots/gap", "gap to the vehicle ahead (m)",
              axis_y=rrb.ScalarAxis(range=(0.0, 3.0 * max(10.0, scenario.target_speed_mps)))),
        _plot("plots/ttc", "time to collision (s, at most 10)",
              axis_y=rrb.ScalarAxis(range=(0.0, 10.0))),
        _plot("plots/accel", "acceleration (m/s^2; hard braking at -3.9)"),
    )


def blueprint(scenario):
    """Cameras and the 3D follow view on top; below, the road map with the colour key |
    offsets, errors and MMAE residuals (cm) | MMAE probabilities, the car's offset (cm),
    steer, throttle and speed, each unit in its own plot | with other vehicles, the gap and
    time to collision to the vehicle ahead and the car's acceleration; events at the bottom.
    Time runs in simulated seconds."""
    import rerun.blueprint as rrb

    x, y, yaw = scenario.start_pose()
    eye = [x - 25.0 * math.cos(yaw), y - 25.0 * math.sin(yaw), 45.0]
    follow = rrb.Spatial3DView(
        origin="world", name="follow view (3D)",
        eye_controls=rrb.EyeControls3D(kind=rrb.Eye3DKind.Orbital, position=eye,
                                       look_target=[x, y, 0.0], eye_up=[0.0, 0.0, 1.0],
                                       tracking_entity="world/car"),
    )
    # Each model's own Kalman track is recorded too ("hough:track"), but left out of the default
    # offsets / errors plots: it shares its model's colour (the selection panel adds it back).
    models = front_labels(scenario.estimation.front_detectors)
    hidden = [f"- $origin/{m}:track" for m in models]
    names = key_names(models)
    traffic = has_other_vehicles(scenario)
    return rrb.Blueprint(
        rrb.Vertical(
            rrb.Horizontal(
                rrb.Spatial2DView(origin="cameras/front", name="front camera"),
                rrb.Spatial2DView(origin="cameras/rear", name="rear camera"),
                follow,
            ),
            # Plots need height: egui's plots label their y grid in steps of a power of ten,
            # and a short plot of a 10 cm range labels only its "0".
            rrb.Horizontal(
                rrb.Vertical(
                    rrb.Spatial2DView(origin="map", name="road map (north up)"),
                    rrb.Spatial2DView(origin=KEY_ORIGIN, name="colour key",
                                      visual_bounds=rrb.VisualBounds2D(**key_bounds(len(names)))),
                    row_shares=[3, 1],
                ),
                rrb.Vertical(
                    _plot("plots/offset", "offsets (cm, + = car left)",
                          contents=["+ $origin/**", *hidden]),
                    _plot("plots/error", "errors (cm, estimate - truth)",
                          contents=["+ $origin/**", *hidden]),
                ),
                rrb.Vertical(
                    _plot("plots/probability", "MMAE probabilities",
                          axis_y=rrb.ScalarAxis(range=(0.0, 1.0))),
                    _plot("plots/residual", "MMAE residuals (cm, reference - model)"),
                ),
                rrb.Vertical(
                    _plot("plots/car", "car: offset from the lane centre (cm)"),
                    _plot("plots/steer", "steer (% of full lock, + = left)"),
                    _plot("plots/throttle", "throttle (%, - = brake)"),
                    # from 0: on its own scale a speed held within 0.1 m/s looked like a
                    # wild ride, and its axis had one label
                    _plot("plots/speed", "speed (m/s)", axis_y=rrb.ScalarAxis(
                        range=(0.0, 1.5 * max(1.0, scenario.target_speed_mps)))),
                ),
                *([_safety_column(scenario)] if traffic else []),
                column_shares=[1.6, 2.6, 2.4, 2.4] + ([2.0] if traffic else []),
            ),
            rrb.TextLogView(origin="events", name="events"),
            row_shares=[3, 6.5, 1],
        ),
        rrb.BlueprintPanel(state="collapsed"),
        rrb.SelectionPanel(state="collapsed"),
        rrb.TimePanel(state="collapsed", timeline=TIMELINE),
    )


# The colour key's entries: KEY_COLUMNS a row, a point each with its label under it. A 2D
# view keeps one scale on both axes, so the key is laid out in about pixels of its panel.
KEY_COLUMNS, KEY_COLUMN_PX, KEY_ROW_PX = 2, 140.0, 36.0


def key_names(models) -> list[str]:
    """The colour key's entries: the truth, the fused output, the reference, each model."""
    return [TRUTH, FUSED, REFERENCE, *models]


def key_positions(n: int) -> list[tuple[float, float]]:
    """Where the colour key puts its n entries."""
    return [((i % KEY_COLUMNS) * KEY_COLUMN_PX, (i // KEY_COLUMNS) * KEY_ROW_PX)
            for i in range(n)]


def key_bounds(n: int) -> dict[str, tuple[float, float]]:
    """The key panel's view: every entry, with room for the labels of the last row."""
    rows = max(1, math.ceil(n / KEY_COLUMNS))
    return {"x_range": (-KEY_COLUMN_PX / 2, (KEY_COLUMNS - 0.5) * KEY_COLUMN_PX),
            "y_range": (-KEY_ROW_PX / 2, (rows - 0.3) * KEY_ROW_PX)}


def scenario_document(scenario) -> str:
    """Markdown that says how to reproduce the recording: command, seed, the scenario's TOML."""
    from lanekeep.scenario.schema import shipped_scenarios

    source = Path(scenario.source) if scenario.source else None
    if source is not None and source.is_file():
        toml = source.read_text(encoding="utf-8")
        shipped = scenario.name in shipped_scenarios() and source.name == f"{scenario.name}.toml"
        where = scenario.name if shipped else str(source)
    else:
        toml, where = f"# not read from a file; the parsed scenario:\n# {scenario!r}", "?"
    return (f"# {scenario.name}\n\nreproduce: `lanekeep run {where} --seed {scenario.seed}`\n\n"
            f"seed {scenario.seed}; duration {scenario.duration_s} s; control period "
            f"{scenario.control_period_s} s\n\n```toml\n{toml}\n```\n")
