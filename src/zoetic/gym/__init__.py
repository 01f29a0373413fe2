"""Gymnasium environments of zoetic animals (``import zoetic.gym`` registers them).

=========================  ==========  ==========================================
id                         animal      task
=========================  ==========  ==========================================
``zoetic/SharkSwim-v0``    shark       swim to a goal 3 m away (random bearing)
``zoetic/DolphinSwim-v0``  dolphin     swim to a goal 3 m away, in the sea
``zoetic/SnakeCrawl-v0``   snake       crawl forward along the start heading
``zoetic/SharkTurn-v0``    shark       turn by a quarter turn, left or right
=========================  ==========  ==========================================

``gymnasium.make(id, render_mode="rgb_array")`` gives a single environment;
``gymnasium.make_vec(id, num_envs, vectorization_mode="vector_entry_point")`` the native
vector environment that steps all copies in one batched kernel call. Spaces, observations
and rewards are described in ``zoetic.gym.envs``; episodes last 200 actions of 0.05 s.
"""

from __future__ import annotations

import gymnasium

from zoetic.gym.envs import ZoeticEnv, ZoeticVectorEnv

ENVS = {
    "zoetic/SharkSwim-v0": {"animal": "shark", "kind": "swim"},
    "zoetic/DolphinSwim-v0": {"animal": "dolphin", "kind": "swim"},
    "zoetic/SnakeCrawl-v0": {"animal": "snake", "kind": "crawl"},
    "zoetic/SharkTurn-v0": {"animal": "shark", "kind": "turn"},
}
MAX_EPISODE_STEPS = 200

for _id, _kwargs in ENVS.items():
    if _id not in gymnasium.registry:
        gymnasium.register(
            id=_id,
            entry_point="zoetic.gym.envs:ZoeticEnv",
            vector_entry_point="zoetic.gym.envs:ZoeticVectorEnv",
            max_episode_steps=MAX_EPISODE_STEPS,
            kwargs=_kwargs,
        )

__all__ = ["ENVS", "ZoeticEnv", "ZoeticVectorEnv"]
