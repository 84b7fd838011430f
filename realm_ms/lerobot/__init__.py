"""LeRobot integration: ``realm export`` (episodes -> LeRobot v3.0 datasets) and the gym adapter behind
the ``realm`` env type of LeRobot's ``lerobot-eval`` / ``lerobot-train`` (package ``lerobot_env_realm``).

Modules: ``features`` (the DROID feature layout both sides share), ``export`` (the dataset writer:
its episodes run on ``realm eval``'s driver with a frame-writing record hook), ``gym_env`` (the
numpy single-env adapter), ``cli`` (``realm export``).
"""
