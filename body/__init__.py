"""The human body shared by the simulator, the tracker and the renderer.

Modules: ``skeleton`` (14 joints, 16 truncated cones, ``BodyDims``), ``pose`` (the 28-DOF pose
vector and its limits), ``kinematics`` (vectorised forward kinematics and cone end points),
``ik`` (joints -> pose vectors), ``camera`` (pinhole camera), ``raster`` (cone sample points,
silhouettes, edge maps), ``bvh`` (motion capture reader), ``trajectory`` (the two-person
interaction file format). World frame: metres, Y up, ground y = 0; a body at yaw 0 faces +Z.
"""
