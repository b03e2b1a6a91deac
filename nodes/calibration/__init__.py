"""The calibration node's package: the camera every node of a graph projects with, published
(latched) on ``camera_info``. :class:`counterpart.nodes.calibration.node.Calibration` (``run: counterpart.nodes.calibration``).

The camera from the people in view, without the bus: ``estimate`` (focal length, tilt, roll and
height from heads and feet against a prior on human height, with scene lines), ``lines`` (scene
line segments grouped by vanishing point), ``observe`` (head/foot points gathered over frames),
``smooth`` (the published camera following the estimates by bounded steps), ``offline``
(``counterpart calibrate``).
"""
