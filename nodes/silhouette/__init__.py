"""Silhouette node: background subtraction with shadow detection, people as regions, B-spline shapes.

Algorithms only (no bus): ``background`` (Horprasert et al. 1999), ``backends`` (ours and OpenCV's
subtractors behind one interface), ``regions`` (clean-up and identity tracking), ``spline``
(closed cubic B-spline boundaries, Baumberg & Hogg; Johnson, Galata & Hogg 1998) and ``pipeline``
(all of it per frame, and offline over a video file).
"""

#: the background subtractors on offer (``backends.make_subtractor``): ours, then OpenCV's. Here,
#: not in ``backends``: the commands list them in their options without importing the algorithms
BACKEND_NAMES: tuple[str, ...] = ("horprasert", "mog2", "knn", "cnt", "gsoc")
