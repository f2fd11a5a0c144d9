"""Traffic that drives: car-following (IDM), lane changes (MOBIL) along smooth Frenet paths,
scripted events (cut-ins, braking leads, stopped vehicles), as pure maths on the road's Frenet
frame (s along the road, r to the left). No MuJoCo here: the world (lanekeep/world/traffic.py)
puts the states on its mocap bodies, scoring reads them as truth, and the car's adaptive
cruise (lanekeep/control/acc.py) uses the same IDM law on its own radar's measurements.
"""
