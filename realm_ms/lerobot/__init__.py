"""LeRobot integration: ``realm export`` (episodes -> LeRobot v3.0 datasets) and the gym adapter behind
the ``realm`` env type of LeRobot's ``lerobot-eval`` / ``lerobot-train`` (package ``lerobot_env_realm``).

Modules: ``features`` (the DROID feature layout both sides share), ``rollout`` (the export's
episode loop), ``export`` (the dataset writer), ``gym_env`` (the numpy single-env adapter),
``cli`` (``realm export``).
"""
