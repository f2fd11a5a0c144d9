"""MJCF assets of lanekeep (the car and a flat test scene), shipped as package data."""

from pathlib import Path

ASSETS_DIR = Path(__file__).resolve().parent
CAR_XML = ASSETS_DIR / "car.xml"
SCENE_XML = ASSETS_DIR / "scene.xml"
