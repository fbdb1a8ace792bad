"""FollowJointTrajectory: the goal read and planned, watched and ended."""
