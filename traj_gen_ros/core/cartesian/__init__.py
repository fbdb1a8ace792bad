"""
Straight lines, blends and arcs of the tool, time-optimal within the joint limits.

Three steps, each its own module: the ideal tool path (:mod:`.tool_path`: lines through
poses with blended corners, the circle through three points), the joint path that
follows it (:mod:`.joint_path`: the continuation of the inverse kinematics, refused where
Craig §7.5's geometric problems arise) and its timing (:mod:`.path_timing`: the
time-optimal ``s(t)`` under joint and tool limits, returned as the core's
:class:`~traj_gen_ros.core.trajectory.Trajectory`). The shared data types are in
:mod:`.samples`. Like :mod:`traj_gen_ros.core.kinematics`, ``import traj_gen_ros`` does
not load this room.
"""
