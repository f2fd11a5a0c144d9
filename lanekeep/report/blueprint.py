"""The rerun viewer's layout for an episode (which panels, where) and the scenario's Markdown
card shown beside them."""

from __future__ import annotations

import math
from pathlib import Path


# -- the blueprint ------------------------------------------------------------------------------
def blueprint(scenario):
    """Cameras side by side; then offsets and errors | the road map and the 3D follow view |
    probabilities, MMAE residuals, car (offset, steer) and speed, each unit in its own plot;
    events below."""
    import rerun.blueprint as rrb

    x, y, yaw = scenario.start_pose()
    eye = [x - 25.0 * math.cos(yaw), y - 25.0 * math.sin(yaw), 45.0]
    top = rrb.Spatial3DView(
        origin="world", name="follow view (3D)",
        eye_controls=rrb.EyeControls3D(kind=rrb.Eye3DKind.Orbital, position=eye,
                                       look_target=[x, y, 0.0], eye_up=[0.0, 0.0, 1.0],
                                       tracking_entity="world/car"),
    )
    legend = rrb.PlotLegend(corner=rrb.Corner2D.LeftTop)
    # Each model's own Kalman track is recorded too ("hough:track"), but left out of the default
    # offsets / errors plots: it shares its model's colour and would double their legends (the
    # selection panel adds it back).
    hidden = [f"- $origin/{m}:track" for m in scenario.estimation.front_detectors]
    return rrb.Blueprint(
        rrb.Vertical(
            rrb.Horizontal(
                rrb.Spatial2DView(origin="cameras/front", name="front camera"),
                rrb.Spatial2DView(origin="cameras/rear", name="rear camera"),
            ),
            rrb.Horizontal(
                rrb.Vertical(
                    rrb.TimeSeriesView(origin="plots/offset", name="offsets (m, + = car left)",
                                       contents=["+ $origin/**", *hidden], plot_legend=legend),
                    rrb.TimeSeriesView(origin="plots/error", name="errors (m, estimate - truth)",
                                       contents=["+ $origin/**", *hidden], plot_legend=legend),
                ),
                rrb.Vertical(
                    rrb.Spatial2DView(origin="map", name="road map (to scale, north up)"),
                    top,
                ),
                rrb.Vertical(
                    rrb.TimeSeriesView(origin="plots/probability", name="MMAE probabilities",
                                       axis_y=rrb.ScalarAxis(range=(0.0, 1.0)),
                                       plot_legend=legend),
                    rrb.TimeSeriesView(origin="plots/residual",
                                       name="MMAE residuals (m, reference - model)",
                                       plot_legend=legend),
                    rrb.TimeSeriesView(origin="plots/car", name="car: offset (m), steer",
                                       plot_legend=legend),
                    rrb.TimeSeriesView(origin="plots/speed", name="car: speed (m/s)",
                                       plot_legend=legend),
                ),
                column_shares=[2, 2, 2],
            ),
            rrb.TextLogView(origin="events", name="events"),
            row_shares=[4, 7, 1.8],
        ),
        rrb.BlueprintPanel(state="collapsed"),
        rrb.SelectionPanel(state="collapsed"),
        rrb.TimePanel(state="collapsed"),
    )


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
