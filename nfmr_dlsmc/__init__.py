"""
nfmr: double-loop sliding-mode trajectory tracking for 4WIS robots (Zhang et al. 2023).

The sub-packages are layers; each imports only from those listed before it
(doc/design.md, Architecture; ``test/test_architecture.py`` keeps it so):

``core``
    the paper's laws, steering geometry, trajectories, gains, metrics (numpy only);
``baselines``
    the comparison laws and the controller registry;
``plants``
    the kinematic and batch models, and the robot plants other packages register;
``runtime``
    node logic without ROS: parameter files, the tracking session, loop statistics;
``bag``
    MCAP writer, reader and reindexer (no rclpy);
``analysis``
    the comparison study, its report and figures, the baseline gain search;
``ros``
    the rclpy nodes, the launcher, replay and run analysis;
``cli``
    the ``nfmr-*`` command lines.

``nfmr_sim`` (the pybullet chassis and its node) builds on this package and registers
itself as the ``pybullet`` plant; nothing here imports it.

The names below are the Python API a script needs to run the paper's scenario::

    from nfmr_dlsmc import DlsmcController, make_trajectory, simulate, simulation_metrics
    run = simulate(DlsmcController(), make_trajectory('sine'), (1.0, 4.0, 0.0), 100.0)
    print(simulation_metrics(run).iae)
"""

from nfmr_dlsmc.core.dlsmc import DlsmcController
from nfmr_dlsmc.core.errors import NfmrError
from nfmr_dlsmc.core.gains import DlsmcConfig, InnerLoopGains, InputLimits, OuterLoopGains
from nfmr_dlsmc.core.metrics import simulation_metrics
from nfmr_dlsmc.core.steering import RobotGeometry, SteerMode, wheel_commands
from nfmr_dlsmc.core.trajectories import make_trajectory
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.plants.kinematic import SimResult, simulate
from nfmr_dlsmc.runtime.params import controller_params, ControllerParams, load_params_file

__all__ = [
    'ControllerParams', 'DlsmcConfig', 'DlsmcController', 'InnerLoopGains', 'InputLimits',
    'NfmrError', 'OuterLoopGains', 'ParameterError', 'RobotGeometry', 'SimResult', 'SteerMode',
    'controller_params', 'load_params_file', 'make_trajectory', 'simulate',
    'simulation_metrics', 'wheel_commands',
]
