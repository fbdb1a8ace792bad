"""The robot's description: a URDF's joints and the joint limits in force."""
