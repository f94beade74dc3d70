"""Steering presets: the sim's ``steer_motors`` and ``--steering`` of the simulating commands."""

from dataclasses import replace
from pathlib import Path

from nfmr_dlsmc.analysis import chassis_tuning, comparison_report, comparison_scenarios
from nfmr_dlsmc.analysis.comparison_runs import results_document
from nfmr_dlsmc.analysis.comparison_scenarios import CASE1_LONGITUDINAL, run_scenario
from nfmr_dlsmc.cli import compare as compare_cli
from nfmr_dlsmc.cli import eval as eval_cli
from nfmr_dlsmc.cli import montecarlo as montecarlo_cli
from nfmr_dlsmc.cli import run as run_cli
from nfmr_dlsmc.cli import tune as tune_cli
from nfmr_dlsmc.cli.common import UsageError
from nfmr_dlsmc.core.steering_presets import STEERING_PRESETS, with_steering
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.ros import launcher
from nfmr_sim.sim_params import sim_settings
from nfmr_sim.world import ChassisWorld
import numpy as np
import pytest
import yaml

ROBOT = 'config/robot_case1.yaml'
SLOW = {'steer_lag': 0.150, 'steer_rate_limit': 2.0}


class _Stop(Exception):
    """Raised by a spy once it has what the test needs: nothing is simulated."""


def _motors(world) -> dict:
    return {key: getattr(world.motors, key) for key in SLOW}


def _step_response(preset: str, seconds: float = 0.8):
    """Return the front-left steer angle [rad] and speed [rad/s] each step after a 1 rad step."""
    with ChassisWorld(sim_settings({'steer_motors': preset}).world) as world:
        world.set_wheel_commands([1.0] * 4, [0.0] * 4)
        out = [world.step() for _ in range(round(seconds / world.config.physics_dt))]
    return (np.array([o.joint_position[0] for o in out]),
            np.array([o.joint_velocity[0] for o in out]))


@pytest.mark.sim
def test_slow_steering_follows_a_step_at_its_rate_limit_and_lags_ideal_does_not():
    angle, speed = _step_response('slow')
    dt = 0.001
    assert np.max(np.abs(speed)) <= 1.02 * 2.0
    # At 2 rad/s alone 0.95 rad is reached at 0.475 s; the 150 ms lag adds its tail
    # (within 0.3 rad of the set point the lag, not the rate limit, sets the speed).
    assert 0.55 < (np.argmax(angle >= 0.95) + 1) * dt < 0.7
    assert angle[-1] == pytest.approx(1.0, abs=0.03)
    angle, speed = _step_response('ideal')
    assert np.max(np.abs(speed)) > 10.0
    assert (np.argmax(angle >= 0.95) + 1) * dt < 0.06


def test_the_file_key_sets_the_motors_and_refuses_explicit_values_beside_it():
    assert _motors(sim_settings({'steer_motors': 'slow'}).world) == SLOW
    assert _motors(sim_settings({'steer_motors': 'servo'}).world) == {
        'steer_lag': 0.050, 'steer_rate_limit': 5.0}
    # '' and ideal: the defaults; an explicit default beside a preset is no conflict.
    assert sim_settings({}).world.motors == sim_settings({'steer_motors': 'ideal'}).world.motors
    assert _motors(sim_settings({'steer_motors': '', 'motors.steer_lag': 0.02}).world)[
        'steer_lag'] == 0.02
    assert _motors(sim_settings({'steer_motors': 'slow',
                                 'motors.steer_rate_limit': 20.0}).world) == SLOW
    with pytest.raises(ParameterError) as error:
        sim_settings({'steer_motors': 'slow', 'motors.steer_rate_limit': 8.0})
    assert str(error.value) == ('motors.steer_rate_limit = 8.0 rad/s: conflicts with '
                                "steer_motors = 'slow': set the preset or the steer motor "
                                'parameters, not both')


def test_an_unknown_preset_in_the_file_is_one_line_naming_it_and_the_choices():
    with pytest.raises(ParameterError) as error:
        sim_settings({'steer_motors': 'fast'})
    assert str(error.value) == "steer_motors = 'fast': must be one of '', ideal, servo, slow"
    with pytest.raises(ParameterError, match=r"^steering = 'fast': must be one of ideal, "
                                             r'servo, slow$'):
        with_steering({}, 'fast')


def test_a_command_line_preset_replaces_the_files_motors_and_its_preset():
    flat = {'steer_motors': 'servo', 'motors.steer_lag': 0.05, 'motors.steer_rate_limit': 5.0,
            'motors.rated_torque': 30.0}
    assert with_steering(flat, 'slow') == {'motors.rated_torque': 30.0,
                                           **STEERING_PRESETS['slow']}


@pytest.mark.parametrize('parser', [eval_cli._parser, run_cli._parser, compare_cli._parser,
                                    montecarlo_cli._parser, tune_cli._parser],
                         ids=['eval', 'run', 'compare', 'montecarlo', 'tune'])
def test_every_command_takes_the_presets_and_refuses_another_in_one_line(parser):
    assert parser().parse_args(['--steering', 'servo']).steering == 'servo'
    assert parser().parse_args([]).steering is None
    with pytest.raises(UsageError) as error:  # exit 2 (run_command)
        parser().parse_args(['--steering', 'fast'])
    assert str(error.value) == ("argument --steering: invalid choice: 'fast' (choose from "
                                "'ideal', 'servo', 'slow')")


def _spy(monkeypatch, module, name, seen):
    """Replace ``module.name`` by a call of it that keeps its result in ``seen``, then stops."""
    real = getattr(module, name)

    def spy(*args, **kwargs):
        seen.append(real(*args, **kwargs))
        raise _Stop
    monkeypatch.setattr(module, name, spy)


@pytest.mark.sim
def test_eval_builds_the_world_of_its_preset(monkeypatch):
    seen = []
    _spy(monkeypatch, eval_cli, 'load_evaluation', seen)
    with pytest.raises(_Stop):
        eval_cli.main(['--plant', 'pybullet', '--params', ROBOT, '--steering', 'slow'])
    assert _motors(seen[0].world) == SLOW


@pytest.mark.sim
def test_eval_refuses_an_unknown_preset_of_the_file_in_one_line(tmp_path, capsys):
    bad = tmp_path / 'bad.yaml'
    document = yaml.safe_load(Path(ROBOT).read_text())
    document['sim']['ros__parameters']['steer_motors'] = 'fast'
    bad.write_text(yaml.safe_dump(document))
    assert eval_cli.main(['--plant', 'pybullet', '--params', str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "steer_motors = 'fast': must be one of '', ideal, servo, slow" in err[0]


@pytest.mark.sim
def test_montecarlo_builds_the_world_of_its_preset(monkeypatch):
    seen = []
    _spy(monkeypatch, montecarlo_cli, 'pybullet_settings', seen)
    with pytest.raises(_Stop):
        montecarlo_cli.main(['--plant', 'pybullet', '--params', ROBOT, '--steering', 'servo',
                             '--n', '2', '--jobs', '1'])
    assert _motors(seen[0].world) == {'steer_lag': 0.050, 'steer_rate_limit': 5.0}


@pytest.mark.sim
def test_compare_hands_its_preset_to_every_run_and_the_run_to_its_world(monkeypatch, tmp_path):
    seen = []
    _spy(monkeypatch, compare_cli, 'comparison_tasks', seen)
    with pytest.raises(_Stop):
        compare_cli.main(['--plant', 'pybullet', '--steering', 'slow', '--out',
                          str(tmp_path / 'report'), '--controllers', 'pid'])
    assert seen[0] and all(task[6] == 'slow' for task in seen[0])
    plant = comparison_scenarios.robot_plant('pybullet')

    class Spy:
        settings = staticmethod(plant.settings)

        @staticmethod
        def simulate(session, x0, duration, world, *rest, **options):
            seen.append(world)
            raise _Stop
    monkeypatch.setattr(comparison_scenarios, 'robot_plant', lambda name: Spy)
    with pytest.raises(_Stop):
        run_scenario('dlsmc', {}, CASE1_LONGITUDINAL, 'pybullet', None, 'slow')
    assert _motors(seen[-1]) == SLOW


def test_compare_and_montecarlo_refuse_the_preset_on_the_kinematic_model(tmp_path, capsys):
    assert compare_cli.main(['--steering', 'slow', '--out', str(tmp_path / 'r')]) == 2
    assert montecarlo_cli.main(['--steering', 'slow', '--n', '2']) == 2
    for line in capsys.readouterr().err.strip().splitlines():
        assert line.endswith('--steering applies to --plant pybullet: the kinematic model '
                             'has no steer motors')
    with pytest.raises(ParameterError, match='^steering = .slow.: applies to the pybullet'):
        run_scenario('dlsmc', {}, CASE1_LONGITUDINAL, 'kinematic', None, 'slow')


@pytest.mark.sim
def test_tune_studies_on_the_chassis_of_its_preset(monkeypatch, tmp_path):
    seen = []
    # nfmr-tune imports the study (the tune extra) when it runs one: spied where it is.
    _spy(monkeypatch, chassis_tuning, 'load_tuning', seen)
    with pytest.raises(_Stop):
        tune_cli.main(['--plant', 'pybullet', '--params', ROBOT, '--steering', 'slow',
                       '--out', str(tmp_path / 'tuned.yaml')])
    tuning = seen[0]
    assert tuning.setup.steering == 'slow'
    assert all(_motors(e.world) == SLOW for e in tuning.evaluations)
    assert tuning.identity()['motors.steer_lag'] == 0.150  # a study of another chassis
    assert tune_cli.main(['--steering', 'slow', '--out', str(tmp_path / 'k.yaml')]) == 2


def test_run_takes_the_preset_and_hands_its_values_to_the_sim_process(monkeypatch):
    seen = []
    monkeypatch.setattr(run_cli, 'run', lambda options: seen.append(options) or 0)
    monkeypatch.setattr(run_cli, 'check_ros_log_folder', lambda: None)
    assert run_cli.main([ROBOT, '--steering', 'slow', '--no-record']) == 0
    options = replace(seen[0], duration=2.0)  # as run() completes them
    assert options.steering == 'slow'
    args = launcher._sim_args(Path(ROBOT), options, (1.0, 4.0, 0.0))
    assert launcher._steering_args(None) == []
    overrides = dict(value.split(':=') for flag, value in zip(args, args[1:]) if flag == '-p')
    assert overrides['steer_motors'] == "''"
    # The sim's parameters: the file's, then the -p overrides (a file's own preset too).
    flat = {'steer_motors': 'servo', **{key: yaml.safe_load(value)
                                        for key, value in overrides.items()}}
    assert _motors(sim_settings(flat).world) == SLOW


@pytest.mark.sim
def test_the_comparison_results_and_report_say_which_steering_ran():
    assert results_document({}, 'pybullet', None, 'slow') == {
        'plant': 'pybullet', 'sensing': 'ideal', 'steering': 'slow'}
    assert 'steering' not in results_document({}, 'pybullet')
    document = {'plant': 'pybullet', 'sensing': 'good', 'steering': 'slow'}
    assert comparison_report._conditions(document) == ', good odometry, slow steering'
    assert comparison_report._steer_rate_limit(document) == 2.0  # the cap the report cites
    assert comparison_report._steer_rate_limit({'plant': 'pybullet'}) == 20.0
