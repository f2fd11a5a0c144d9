"""Real cameras: camera files, OpenCV calibration from chessboard photos, strict image reading,
frame sequences and videos."""
