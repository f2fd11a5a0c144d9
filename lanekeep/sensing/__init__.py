"""What the car senses: the onboard cameras and their renders, lens and weather effects, the
camera's
image chain, and the vehicle's sensor signals (wheel speed, IMU, steering)."""
