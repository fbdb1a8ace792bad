"""The speed override: its inputs, the ramp of the plan clock and its look-ahead."""
