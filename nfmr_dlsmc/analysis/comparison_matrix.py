"""
The steering and sensing matrix of ``nfmr-compare --matrix``: which law to choose on which robot.

Case 1 from (1, 4, 0) and the lemniscate from (1, -1, 0.5), each for every steering preset
(:data:`~nfmr_dlsmc.core.steering_presets.STEERING_PRESETS`) and the sensing presets
``good`` and ``harsh`` (:data:`~nfmr_dlsmc.core.sensing.SENSING_PRESETS`), for the robot
profile of the DLSMC, Stanley, Kanayama and pure pursuit, on the pybullet chassis. The robot
profile declares each cell's steering (its ``steer_lag`` and ``steer_rate_limit`` are the
preset's) and odometry noise (its ``odom_position_noise`` and ``odom_yaw_noise`` are the
sensing preset's, doc/design.md D39), and every law sees the pose through the robot
profile's estimator (:func:`~nfmr_dlsmc.analysis.comparison_scenarios.run_scenario`
with a sensing preset). The runs are those of
:func:`~nfmr_dlsmc.analysis.comparison_runs.run_all`; what they measured goes into
``matrix.json``, its tables (:func:`matrix_tables`) into ``matrix.md`` and a heat map per
law into ``matrix.png``.
"""

from dataclasses import replace

from nfmr_dlsmc.analysis.comparison_scenarios import CASE1_LONGITUDINAL, Scenario
from nfmr_dlsmc.baselines.registry import controller_label
from nfmr_dlsmc.core.disturbances import YawRateDisturbance
from nfmr_dlsmc.core.metrics import COARSE_TOLERANCE, HOLD_FROM
from nfmr_dlsmc.core.sensing import SENSING_PRESETS
from nfmr_dlsmc.core.steering_presets import STEERING_PRESETS
from nfmr_dlsmc.core.trajectories import make_trajectory

#: The laws of the matrix, in its columns: the robot profile first.
MATRIX_LAWS = ('dlsmc_robot', 'stanley', 'kanayama', 'pure_pursuit')
#: The laws that declare each cell's steering and odometry noise (their blocks take
#: ``steer_lag``, ``steer_rate_limit``, ``odom_position_noise`` and ``odom_yaw_noise``):
#: the robot profile. The paper's DLSMC stays the paper's law.
DECLARING_LAWS = ('dlsmc_robot',)
#: The steering presets (rows, outer) and sensing presets (rows, inner) of the matrix.
MATRIX_STEERING = tuple(STEERING_PRESETS)
MATRIX_SENSING = ('good', 'harsh')
#: The references, by the key of ``matrix.json``: Case 1 from (1, 4, 0) and the
#: lemniscate (its default parameters) from (1, -1, 0.5).
MATRIX_SCENARIOS = {
    'case1': CASE1_LONGITUDINAL,
    'lemniscate': Scenario('lemniscate', (1.0, -1.0, 0.5), YawRateDisturbance(),
                           trajectory=make_trajectory('lemniscate')),
}
#: Their titles in ``matrix.md`` and ``matrix.png``.
SCENARIO_TITLES = {'case1': 'Case 1 (the sine) from (1, 4, 0)',
                   'lemniscate': 'The lemniscate from (1, -1, 0.5)'}
#: Length of every run [s] unless ``--duration`` says otherwise.
MATRIX_DURATION = 40.0
#: A cell's steer joints count as running at their rate limit when the 99th percentile of
#: the fastest joint's rate over the hold is at least this share of the preset's limit.
RATE_LIMIT_SHARE = 0.95
#: What marks a run: the sign ``matrix.md`` and ``matrix.png`` give it, what it says, and
#: that in a few words (the figure's).
MARKS = {
    'omega_saturated': ('†', 'ω at its limit on ticks of the hold', 'ω saturated'),
    'steer_rate_limit': ('‡', f'the steer joints at ≥ {100.0 * RATE_LIMIT_SHARE:g} % of the '
                              'steering rate limit for ≥ 1 % of the hold (the 99th '
                              "percentile of the fastest joint's rate there)",
                         'steer joints at their rate limit'),
    'not_converged': ('✗', f'farther than {100.0 * COARSE_TOLERANCE:g} cm from the reference '
                           'at the end of the run',
                      f'not within {100.0 * COARSE_TOLERANCE:g} cm at the end'),
}


def cell_name(steering: str, sensing: str) -> str:
    """Return the key of a cell in ``matrix.json``, e.g. ``"servo/good"``."""
    return f'{steering}/{sensing}'


def matrix_cells() -> list[tuple[str, str]]:
    """Return (steering, sensing) of every cell, in the order of the tables' rows."""
    return [(steering, sensing) for steering in MATRIX_STEERING for sensing in MATRIX_SENSING]


def declared_block(name: str, block: dict | None, steering: str, sensing: str) -> dict | None:
    """
    Return law ``name``'s gain block for a cell of presets ``steering`` and ``sensing``.

    A law of :data:`DECLARING_LAWS` gets the steering preset's ``motors.steer_lag`` as its
    ``steer_lag`` [s] and ``motors.steer_rate_limit`` as its ``steer_rate_limit`` [rad/s]
    (doc/steering.md), and the sensing preset's ``disturbance.odom_position_noise`` [m] and
    ``disturbance.odom_yaw_noise`` [rad] as its ``odom_position_noise`` and
    ``odom_yaw_noise`` (doc/design.md, D39); the other laws' blocks are returned as they are.
    """
    if name not in DECLARING_LAWS:
        return block
    motors, odometry = STEERING_PRESETS[steering], SENSING_PRESETS[sensing]
    return {**(block or {}), 'steer_lag': motors['motors.steer_lag'],
            'steer_rate_limit': motors['motors.steer_rate_limit'],
            'odom_position_noise': odometry['disturbance.odom_position_noise'],
            'odom_yaw_noise': odometry['disturbance.odom_yaw_noise']}


def matrix_tasks(blocks: dict, duration: float = MATRIX_DURATION,
                 laws=MATRIX_LAWS) -> list[tuple]:
    """
    Return every run of the matrix as a task of :func:`~.comparison_runs.run_all`.

    Each reference of :data:`MATRIX_SCENARIOS` for ``duration`` [s], in every cell of
    :func:`matrix_cells`, for every law of ``laws`` with its block of ``blocks`` (a gains
    file's, :func:`declared_block`); the key is (reference, cell, law).
    """
    tasks = []
    for key, scenario in MATRIX_SCENARIOS.items():
        scenario = replace(scenario, duration=duration)
        for steering, sensing in matrix_cells():
            tasks += [((key, cell_name(steering, sensing), name), name,
                       declared_block(name, blocks.get(name), steering, sensing), scenario,
                       'pybullet', sensing, steering) for name in laws]
    return tasks


def matrix_document(metrics: dict, laws, duration: float, odom_seed: int = 0) -> dict:
    """
    Return ``matrix.json``'s document of the runs' ``metrics`` (by task key).

    ``"laws"`` -> ``laws`` in column order; ``"duration"`` [s] and ``"hold_from"`` [s];
    ``"odom_seed"`` -> the seed of the odometry's noise;
    ``"references"`` -> reference -> its trajectory and start pose; ``"cells"`` -> cell ->
    its steering and sensing presets and the steering's ``steer_lag`` [s] and
    ``steer_rate_limit`` [rad/s]; ``"runs"`` -> reference -> cell -> law -> every number
    of :func:`~nfmr_dlsmc.analysis.comparison_metrics.run_metrics`.
    """
    references = {key: {'trajectory': type(s.trajectory).__name__.lower() if s.trajectory
                        else 'sine', 'x0': list(s.x0)} for key, s in MATRIX_SCENARIOS.items()}
    cells = {cell_name(steering, sensing): {
        'steering': steering, 'sensing': sensing,
        'steer_lag': STEERING_PRESETS[steering]['motors.steer_lag'],
        'steer_rate_limit': STEERING_PRESETS[steering]['motors.steer_rate_limit']}
        for steering, sensing in matrix_cells()}
    runs = {}  # in the order of the tables, whatever the order the runs ended in
    for reference in MATRIX_SCENARIOS:
        for cell in cells:
            for name in laws:
                if (reference, cell, name) in metrics:
                    runs.setdefault(reference, {}).setdefault(cell, {})[name] = metrics[
                        (reference, cell, name)]
    return {'plant': 'pybullet', 'laws': list(laws), 'duration': duration,
            'hold_from': HOLD_FROM, 'odom_seed': odom_seed, 'references': references,
            'cells': cells, 'runs': runs}


def run_marks(figures: dict, rate_limit: float) -> tuple[str, ...]:
    """
    Return the keys of :data:`MARKS` that one run's figures earn.

    ``omega_saturated``: ω at its limit on any tick of the hold; ``steer_rate_limit``: the
    fastest steer joint's rate p99 over the hold at least :data:`RATE_LIMIT_SHARE` of
    ``rate_limit`` [rad/s]; ``not_converged``: farther than 1 cm at the end of the run
    (no ``t_conv_1cm``). A figure the run does not have (a run shorter than the hold
    window) earns no mark.
    """
    marks = []
    if (figures.get('hold_omega_saturated') or 0.0) > 0.0:
        marks.append('omega_saturated')
    rate = figures.get('hold_steer_joint_rate_p99')
    if rate is not None and rate >= RATE_LIMIT_SHARE * rate_limit:
        marks.append('steer_rate_limit')
    if figures.get('t_conv_1cm') is None:
        marks.append('not_converged')
    return tuple(marks)


def choose_law(runs: dict, rate_limit: float) -> str | None:
    """
    Return the law to choose in one cell: the closest hold of the laws without a mark.

    ``runs`` is law -> figures of one cell of ``matrix.json``, ``rate_limit`` the cell's
    steering rate limit [rad/s]. Of the laws with a ``hold_distance_p99`` and no mark
    (:func:`run_marks`: ω never saturated in the hold, the steer joints off their limit,
    within 1 cm at the end), the one with the smallest; None when no law is so.
    """
    fit = [(figures['hold_distance_p99'], name) for name, figures in runs.items()
           if figures.get('hold_distance_p99') is not None
           and not run_marks(figures, rate_limit)]
    return min(fit)[1] if fit else None


def _millimetres(distance: float) -> str:
    """Format a distance [m] in millimetres with three significant digits or more."""
    mm = 1000.0 * distance
    if mm < 10.0:
        return f'{mm:.2f}'
    return f'{mm:.1f}' if mm < 100.0 else f'{mm:.0f}'


def cell_text(figures: dict | None, rate_limit: float) -> str:
    """Return a run's hold distance p99 in mm and its marks' signs (— without a figure)."""
    if figures is None:
        return 'not run'
    signs = ''.join(MARKS[mark][0] for mark in run_marks(figures, rate_limit))
    p99 = figures.get('hold_distance_p99')
    text = '—' if p99 is None else _millimetres(p99)
    return f'{text} {signs}' if signs else text


def matrix_tables(document: dict) -> str:
    """
    Return the tables of ``matrix.md`` of a ``matrix.json`` document, one per reference.

    A row per cell (steering, sensing), a column per law: its hold distance p99 in mm with
    the signs of :data:`MARKS`, the smallest of the row in bold; the last column, the law
    :func:`choose_law` picks. A legend of the signs follows.
    """
    laws = document['laws']
    lines = []
    for reference, cells in document['runs'].items():
        lines += [f'### {SCENARIO_TITLES.get(reference, reference)}', '',
                  '| steering, sensing | ' + ' | '.join(controller_label(n) for n in laws)
                  + ' | choose |', '|---|' + '---:|' * len(laws) + '---|']
        for cell, info in document['cells'].items():
            runs = cells.get(cell, {})
            rate_limit = info['steer_rate_limit']
            held = {n: runs[n]['hold_distance_p99'] for n in laws
                    if n in runs and runs[n].get('hold_distance_p99') is not None}
            best = min(held.values()) if held else None
            texts = []
            for name in laws:
                text = cell_text(runs.get(name), rate_limit)
                texts.append(f'**{text}**' if best is not None and held.get(name) == best
                             else text)
            choice = choose_law(runs, rate_limit)
            lines.append(f"| {info['steering']} ({1000.0 * info['steer_lag']:g} ms, "
                         f"{rate_limit:g} rad/s), {info['sensing']} | " + ' | '.join(texts)
                         + f" | {'none' if choice is None else controller_label(choice)} |")
        lines.append('')
    lines.append('Hold distance p99 [mm] from t = '
                 f"{document['hold_from']:g} s on, of the ground truth; in bold the smallest "
                 'of the row. ' + '; '.join(f'{sign} {text}' for sign, text, _ in MARKS.values())
                 + '. *choose*: of the laws without a mark, the one with the smallest p99 '
                 '(none: every law is marked).')
    return '\n'.join(lines) + '\n'


def matrix_report(document: dict, gains: str, elapsed: float, where: str) -> str:
    """
    Return ``matrix.md``: what ran and :func:`matrix_tables`.

    ``gains`` is the comparison gains file the laws' blocks came from, ``elapsed`` the wall
    time of the runs [s] and ``where`` where they ran (e.g. "2 processes").
    """
    runs = sum(len(laws) for cells in document['runs'].values() for laws in cells.values())
    return (
        '# nfmr comparison matrix — pybullet chassis, steering × sensing\n\n'
        f"{runs} runs of {document['duration']:g} s ({elapsed:.0f} s on {where}): every "
        'reference, steering preset and sensing preset for '
        f"{', '.join(controller_label(n) for n in document['laws'])}, their gains from "
        f'{gains}. The robot profile declares the steering and the odometry noise of each '
        'row (`steer_lag`, `steer_rate_limit`, `odom_position_noise`, `odom_yaw_noise`: the '
        "presets'); every law sees the pose through the robot profile's estimator, the "
        f"odometry's noise drawn with seed {document['odom_seed']}. `matrix.json` has "
        'every number of every run, `matrix.png` the heat maps.\n\n' + matrix_tables(document))
