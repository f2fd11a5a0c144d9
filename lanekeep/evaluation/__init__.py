"""Open-loop evaluation of detectors: the LaneNet dataset, the fixed eval sets, lane metrics (AP,
IoU, ADE, FDE), detectors on real photos and videos (`lanekeep detect`)."""
