"""The calibration node's package: the camera every node of a graph projects with, published once
(latched) on ``camera_info``. :class:`nodes.calibration.node.Calibration` (``run: nodes.calibration``)."""
