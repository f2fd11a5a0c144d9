"""`builtin_family`: the registered detector a plug-in inherits from, so that the loop gives it
what it measured for that detector (tracker noise, paper windows, LaneNet batching)."""

import dataclasses
import math

import numpy as np
from plugins.sham import OwnDetect, Sham, ShamHough, ShamOfSham, Unrelated

from lanekeep.detectors.config import load_config
from lanekeep.detectors.hough import HoughDetector
from lanekeep.detectors.lanenet import LaneNetDetector
from lanekeep.detectors.registry import builtin_family, make_detector
from lanekeep.driver.detection import _batch_key
from lanekeep.geometry.camera_model import CameraModel


def test_a_subclass_of_a_built_in_is_of_its_family():
    assert builtin_family(Sham) == "lanenet"
    assert builtin_family(ShamOfSham) == "lanenet"  # the nearest registered ancestor
    assert builtin_family(ShamHough) == "hough"
    assert builtin_family("plugins.sham:Sham") == "lanenet"  # by import path, as a scenario


def test_a_built_in_is_its_own_family():
    assert builtin_family(LaneNetDetector) == "lanenet"
    assert builtin_family(HoughDetector) == "hough"
    assert builtin_family("sliding_window") == "sliding_window"


def test_a_plug_in_that_subclasses_no_built_in_has_none():
    assert builtin_family(Unrelated) is None
    assert builtin_family(Unrelated()) is None
    assert builtin_family("plugins.byo:MedianHough") is None  # wraps Hough, does not inherit


def test_a_lanenet_subclass_batches_with_lanenet_unless_it_overrides_detect():
    """The loop's batch key (lanekeep/loop/detection.py): a subclass that keeps LaneNet's
    `detect` shares LaneNet's key (one network call with the LaneNet reference); one that
    overrides `detect` gets its own, so that a batch never skips the override."""
    def bare(cls):
        detector = object.__new__(cls)  # no weights loaded: the key reads the class and path
        detector.weights_path = "w.pt"
        return detector

    key = _batch_key(bare(LaneNetDetector))
    assert _batch_key(bare(Sham)) == key
    assert _batch_key(bare(ShamOfSham)) == key
    assert _batch_key(bare(OwnDetect)) == (OwnDetect, "w.pt")


def test_a_subclass_keeping_the_constructor_reads_its_built_ins_settings_table():
    """A `[lanenet]` table reaches a sham of LaneNet as it reaches LaneNet (make_detector)."""
    k = np.array([[184.6, 0.0, 159.5], [0.0, 184.6, 89.5], [0.0, 0.0, 1.0]])
    front = CameraModel.from_mounting("front", k, 320, 180, 1.5, math.radians(10.0), x_m=1.0)
    config = dataclasses.replace(load_config(), tables={"lanenet": {"score_threshold": 0.6}})
    built_in = make_detector("lanenet", front, config)
    sham = make_detector("plugins.sham:Sham", front, config)
    assert sham.settings == built_in.settings
    assert sham.settings.score_threshold == 0.6
