"""The tracker node: 3D articulated tracking of up to two people from silhouettes and edges.

Modules: ``likelihood`` (silhouette/edge/coverage observation model over projected cones),
``apf`` (annealed particle filter, Deutscher et al. 2000, and a plain particle filter), ``prior``
(PCA + HMM motion prior, Zheng et al. 2006), ``init`` (placement from a silhouette, lost tracks),
``tracker`` (``Tracker`` per person, ``track_sequence`` offline), ``node`` (the bus node),
``cli_learn`` (``counterpart learn tracker-prior``).
"""
