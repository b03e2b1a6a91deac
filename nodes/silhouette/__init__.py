"""Silhouette node: background subtraction with shadow detection, people as regions, B-spline shapes.

Algorithms only (no bus): ``background`` (Horprasert et al. 1999), ``backends`` (ours and OpenCV's
subtractors behind one interface), ``regions`` (clean-up and identity tracking), ``spline``
(closed cubic B-spline boundaries, Baumberg & Hogg; Johnson, Galata & Hogg 1998) and ``pipeline``
(all of it per frame, and offline over a video file).
"""
