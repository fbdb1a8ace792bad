"""The setpoint stream: the schedule of motions, sampled and published every tick."""
