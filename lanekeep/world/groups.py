"""MuJoCo geom groups: which geoms each render draws. The world assigns them (build.py and the
condition modules, mjcf/car.xml for the car); the cameras (lanekeep/sensing/cameras.py) choose
which groups each render shows. Defined once, here."""

GROUP_WORLD = 0
GROUP_MARKING = 1  # paint drawn as geometry in both renders: raised dots, worn paint
GROUP_CAR_BODY = 2  # the ego car's body and tyres (mjcf/car.xml): seen by neither camera
GROUP_UNSEEN = GROUP_CAR_BODY  # any geom neither camera draws (the contact ground plane)
GROUP_MARKING_LABEL = 3  # fresh paint geometry: the segmentation render only
GROUP_HOOD = 4  # the ego car's hood: seen by the front camera when `show_hood` is on
# Translucent geoms of the RGB render only: shadows, puddles, snow bands and the filtered
# fresh paint (lanekeep/world/paint.py); hidden from the segmentation render.
GROUP_RGB_OVERLAY = 5
GROUP_SHADOW = GROUP_RGB_OVERLAY
