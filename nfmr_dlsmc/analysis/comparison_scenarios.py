"""
The paper's comparison scenarios (section 4.2).

The sine reference, 100 s at 1 ms, Case 1 from two starts without disturbance, Case 2
with the yaw-rate pulses; on the kinematic model (3) or the pybullet chassis. Also a path
of the user's, from its start to its end, with the same arrival rule for every law.
"""

from dataclasses import dataclass
import math

from nfmr_dlsmc.baselines.registry import build_controller
from nfmr_dlsmc.core.arrival import ArrivalConfig, with_arrival
from nfmr_dlsmc.core.disturbances import paper_disturbance, YawRateDisturbance
from nfmr_dlsmc.core.dlsmc import DlsmcController
from nfmr_dlsmc.core.gains import DlsmcConfig
from nfmr_dlsmc.core.pose_estimator import EstimatorConfig
from nfmr_dlsmc.core.sensing import with_controller_sensing, with_sensing
from nfmr_dlsmc.core.steering import RobotGeometry, SteerMode
from nfmr_dlsmc.core.steering_presets import with_steering
from nfmr_dlsmc.core.trajectories import make_trajectory
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.plants.kinematic import SimResult, simulate, with_steer_angles
from nfmr_dlsmc.plants.registry import robot_plant
from nfmr_dlsmc.runtime.params import (
    controller_params,
    ControllerParams,
    load_params_file,
    session_options,
)
from nfmr_dlsmc.runtime.share import shipped_config
from nfmr_dlsmc.runtime.tracking_session import TrackingSession

#: The plants a scenario runs on: the unicycle model (3), forward Euler; the simulated
#: 4WIS chassis (Table 1, double Ackermann) in this process.
PLANTS = ('kinematic', 'pybullet')


@dataclass(frozen=True)
class Scenario:
    """
    One run of the comparison: a case, a start and a disturbance.

    Attributes
    ----------
    case : str
        ``"case1"``, ``"case2"`` or ``"path"``.
    x0 : tuple of 3 floats
        Initial pose (x [m], y [m], theta [rad]).
    disturbance : YawRateDisturbance
    duration : float
        [s]
    dt : float
        Control and integration period [s].
    trajectory : object or None
        The reference; None: the paper's sine.
    arrival : ArrivalConfig or None
        With a reference that ends (a path), when a controller has arrived and stops
        (:func:`~nfmr_dlsmc.core.arrival.with_arrival`), the same rule for every law.
    odom_seed : int
        With a sensing preset: the seed of the odometry's noise and bias walk (the sim's
        ``disturbance.seed``); one draw of a noisy odometry, the same for every law.

    """

    case: str
    x0: tuple
    disturbance: YawRateDisturbance
    duration: float = 100.0
    dt: float = 0.001
    trajectory: object = None
    arrival: ArrivalConfig | None = None
    odom_seed: int = 0

    @property
    def start_key(self) -> str:
        """Return the start as the key of ``results.json``, e.g. ``"1,4,0"``."""
        return ','.join(f'{value:.6g}' for value in self.x0)


#: Case 1 (a) large lateral error, (b) large longitudinal error (Fig. 7), no disturbance.
CASE1_LATERAL = Scenario('case1', (4.0, 1.0, 0.0), YawRateDisturbance())
CASE1_LONGITUDINAL = Scenario('case1', (1.0, 4.0, 0.0), YawRateDisturbance())
#: Case 2: x0 = (1, 1, pi/6), 0.5 rad/s yaw-rate pulses at 5 s and 50 s.
CASE2 = Scenario('case2', (1.0, 1.0, math.pi / 6.0), paper_disturbance())
SCENARIOS = (CASE1_LONGITUDINAL, CASE1_LATERAL, CASE2)


def robot_estimator() -> EstimatorConfig:
    """Return the pose estimator of the robot profile (``config/robot_case1.yaml``)."""
    return controller_params(load_params_file(shipped_config('robot_case1.yaml'))).estimator


def run_scenario(name: str, block: dict | None, scenario: Scenario,
                 plant: str = 'kinematic', sensing: str | None = None,
                 steering: str | None = None) -> SimResult:
    """
    Run controller ``name`` with gain block ``block`` on ``scenario`` and ``plant``.

    The scenario's reference (the paper's sine unless it gives one) and the paper's limits;
    along a path every law stops by the scenario's arrival rule. ``plant`` is one of
    :data:`PLANTS`. On the kinematic model the result's ``steer`` holds the steer angles
    [rad] the double Ackermann mapping would command for (v, omega + disturbance); on
    pybullet the disturbance is added to omega
    before the wheel mapping and the chassis is that of the default world of the registered
    ``pybullet`` plant (Table 1, physics at 1 ms). With a ``sensing`` preset (pybullet
    only) the world's odometry is the preset's and every law sees the pose through the
    robot profile's estimator (``config/robot_case1.yaml``), so that all compare alike
    (under ``field`` each fuses the wheel odometry with the fixes, D33);
    with a ``steering`` preset (pybullet only) the steer motors are the preset's.
    """
    if plant not in PLANTS:
        raise ValueError(f"plant must be one of {', '.join(PLANTS)}, got {plant!r}")
    if sensing is not None and plant != 'pybullet':
        raise ParameterError('sensing', sensing, 'applies to the pybullet plant: the '
                             'kinematic model has no odometry')
    if steering is not None and plant != 'pybullet':
        raise ParameterError('steering', steering, 'applies to the pybullet plant: the '
                             'kinematic model has no steer motors')
    trajectory = scenario.trajectory or make_trajectory('sine')
    law = build_controller(name, block, dt=scenario.dt)
    if plant == 'pybullet':
        plant_ = robot_plant('pybullet')
        flat = {} if sensing is None else with_sensing({}, sensing) | {
            'disturbance.seed': scenario.odom_seed}
        settings = plant_.settings(flat if steering is None else with_steering(flat, steering))
        # The session leads the steer set points as the law's own options say (D41).
        dlsmc = law.config if isinstance(law, DlsmcController) else DlsmcConfig(dt=scenario.dt)
        params = ControllerParams(
            dlsmc=dlsmc, trajectory=trajectory, arrival=scenario.arrival,
            estimator=EstimatorConfig() if sensing is None else robot_estimator(),
            fusion=controller_params(with_controller_sensing({}, sensing)).fusion)
        return plant_.simulate(TrackingSession(params, **session_options({}), law=law),
                               scenario.x0, scenario.duration, settings.world,
                               scenario.disturbance, encoders=settings.encoders)
    result = simulate(with_arrival(law, trajectory, scenario.arrival), trajectory, scenario.x0,
                      scenario.duration, scenario.dt, scenario.disturbance)
    return with_steer_angles(result, RobotGeometry(), SteerMode())
