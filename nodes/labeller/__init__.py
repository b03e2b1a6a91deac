"""Social-signal labeller (Okwechime et al., "Social interactive human video synthesis").

Per person and frame: head nod and head shake (FFT of head motion relative to the torso), activity
(torso motion), gaze at the other person (head/torso yaw against the direction to the other), and
talking/laughing where a face is visible at enough resolution. Offline: Apriori association rules
between a speaker's signals and a listener's response ``s`` frames later (:mod:`.mining`).

The algorithms are plain modules over numpy arrays; the bus wrapper lives in ``node.py``.
"""

from counterpart.nodes.labeller.signals import JOINTS, SIGNALS, UNKNOWN

__all__ = ["JOINTS", "SIGNALS", "UNKNOWN"]
