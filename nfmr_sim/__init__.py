"""pybullet simulation of the 4WIS chassis (ROS-free world) and its ROS 2 node."""
