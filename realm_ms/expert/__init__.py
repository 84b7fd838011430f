"""Privileged scripted expert for every REALM task (IK on the robot's own model, droid_joint_pos).

    from realm_ms.expert import make_expert, run_episode
    res = run_episode(env, seed=0)   # {'progression', 'success', 'stalled_stage', 'steps', 'log'}
"""

from realm_ms.expert.core import Expert, make_expert, run_episode, start_episode  # noqa: F401
from realm_ms.expert.skills import SKILLS  # noqa: F401
