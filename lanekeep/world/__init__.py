"""The simulated world built with MjSpec from a scenario: road, paint, pavement, roadside, props,
traffic, lighting and the car. The simulator's truth lives here; nothing above reads it but
scoring and report."""
