"""The scripted expert as an evaluated policy: privileged, so it runs next to the env (``env_side``)."""

from __future__ import annotations

from realm_ms.eval.policies import POLICIES
from realm_ms.eval.policies.policy import Policy


class ExpertPolicy(Policy):
    name = "expert"
    env_side = True

    def bind_env_policy(self, env):
        from realm_ms.expert import make_expert

        return make_expert(env)


POLICIES.register("expert", lambda arg, **kw: ExpertPolicy())
