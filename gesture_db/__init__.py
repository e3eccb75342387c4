"""Gesture database: simulated and imported recordings, segmentation, contours, features."""
