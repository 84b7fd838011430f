"""Torque-space system identification: data with measured joint torque, no ``q_cmd`` needed."""
