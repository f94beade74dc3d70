"""
The paper's laws and what they stand on: numpy, scipy and the standard library only.

scipy fits the splines of a path given as points.

Errors and checks, angles, gains, the sliding functions, the outer (BTINTSMC) and inner
(ABFSMC) loops, the double-loop cascade, trajectories, the double-Ackermann steering
geometry, disturbances and the paper's figures of merit. Imports nothing else of nfmr.
"""
