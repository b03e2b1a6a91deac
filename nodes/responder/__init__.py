"""The responder: learned interaction models that produce the virtual partner.

Models (each a scikit-learn-style class over numpy arrays, usable without the bus):

* :class:`~counterpart.nodes.responder.dual_hmm.DualHMM` (Zheng et al. 2006; Cosker et al. 2004): one Gaussian
  HMM over both people's PCA-reduced, actor-centred 3D poses; the partner is read off by Gaussian
  conditioning on the observed person; its parts in ``pair_features``, ``hmm_blocks``,
  ``conditioning``, ``forward_filter``, ``placement_kalman`` and ``placement_correction``.
* :class:`~counterpart.nodes.responder.joint_shape.JointShapeModel` (Johnson, Galata & Hogg 1998): joint
  B-spline silhouettes, state and behaviour prototypes, a Markov chain, CONDENSATION.
* :class:`~counterpart.nodes.responder.listener.ListenerModel` (Okwechime et al.): listener behaviour chosen by
  mined rule confidences at a user-set interest level.
* :class:`~counterpart.nodes.responder.emotion.EmotionModel` (Chan et al.; Taubert et al.): relative-attribute
  ranking of emotion strength and a continuous style that modulates the generated motion.

Model files: :mod:`counterpart.nodes.responder.models`. The node: :mod:`counterpart.nodes.responder.node`.
"""
