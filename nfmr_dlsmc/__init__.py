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
    the comparison study, its report and figures, run metrics and plots, the baseline gain
    search;
``ros``
    the rclpy nodes, the launcher, replay and recorded runs decoded;
``cli``
    the ``nfmr-*`` command lines.

``nfmr_sim`` (the pybullet chassis and its node) builds on this package and registers
itself as the ``pybullet`` plant; nothing here imports it.

The names below are the Python API a script needs to run the paper's scenario::

    from nfmr_dlsmc import DlsmcController, make_trajectory, simulate, simulation_metrics
    run = simulate(DlsmcController(), make_trajectory('sine'), (1.0, 4.0, 0.0), 100.0)
    print(simulation_metrics(run).iae)
"""

import importlib

#: The public names and the module each comes from: imported when first used (PEP 562), so
#: that a command is interruptible from its first instant instead of after a second of
#: imports (numpy, scipy) in this package's import.
_API = {
    'DlsmcController': 'nfmr_dlsmc.core.dlsmc', 'NfmrError': 'nfmr_dlsmc.core.errors',
    'DlsmcConfig': 'nfmr_dlsmc.core.gains', 'InnerLoopGains': 'nfmr_dlsmc.core.gains',
    'InputLimits': 'nfmr_dlsmc.core.gains', 'OuterLoopGains': 'nfmr_dlsmc.core.gains',
    'simulation_metrics': 'nfmr_dlsmc.core.metrics', 'RobotGeometry': 'nfmr_dlsmc.core.steering',
    'SteerMode': 'nfmr_dlsmc.core.steering', 'wheel_commands': 'nfmr_dlsmc.core.steering',
    'make_trajectory': 'nfmr_dlsmc.core.trajectories',
    'ParameterError': 'nfmr_dlsmc.core.validation', 'SimResult': 'nfmr_dlsmc.plants.kinematic',
    'simulate': 'nfmr_dlsmc.plants.kinematic', 'controller_params': 'nfmr_dlsmc.runtime.params',
    'ControllerParams': 'nfmr_dlsmc.runtime.params',
    'load_params_file': 'nfmr_dlsmc.runtime.params',
}
__all__ = sorted(_API)


def __getattr__(name):
    """Return a public name, importing its module on first use."""
    if name not in _API:
        raise AttributeError(f"module 'nfmr_dlsmc' has no attribute {name!r}")
    value = getattr(importlib.import_module(_API[name]), name)
    globals()[name] = value
    return value


def __dir__():
    """List the public names with the module's own."""
    return sorted({*globals(), *_API})
