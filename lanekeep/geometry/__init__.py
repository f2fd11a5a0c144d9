"""Pure geometry, no MuJoCo: the road in Frenet form, its meshes, the marking layout, the pinhole
camera model and lens distortion."""
