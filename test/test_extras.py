"""
The extras: the nodes need none of them, and a feature without its extra says so in one line.

setup.py's ``install_requires`` is what the controller and sim nodes need; matplotlib and
Pillow (``plots``), Optuna and SQLAlchemy (``tune``) and Dask's distributed (``cluster``)
are extras, named by :data:`nfmr_dlsmc.runtime.extras.EXTRAS`. A package is made missing
here as Python has it when it is not installed: ``sys.modules[name] = None`` makes its
import fail. test_bare_install.py installs the package without extras for real.
"""

import ast
from importlib import metadata
from pathlib import Path
import subprocess
import sys

from nfmr_dlsmc import controller_params, DlsmcController, simulate
from nfmr_dlsmc.ros.launcher import RunOptions
from nfmr_dlsmc.ros.run_report import report_run
from nfmr_dlsmc.runtime.extras import EXTRAS, missing, MissingExtra, require
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name
import pytest
from synthetic_bags import write_run_bag

ROOT = Path(__file__).resolve().parents[1]
#: The modules of every extra, and Dask's own (which distributed imports).
EXTRA_MODULES = sorted({module for modules in EXTRAS.values() for module in modules} | {'dask'})
#: The modules of the console scripts nfmr-controller and nfmr-sim.
NODES = ['nfmr_dlsmc.ros.controller_node', 'nfmr_sim.ros.sim_node']
#: Every command's module: each starts without the extras, only its features need them.
COMMANDS = sorted(f'nfmr_dlsmc.cli.{path.stem}' for path in (ROOT / 'nfmr_dlsmc' / 'cli').glob(
    '*.py') if path.stem != '__init__')


def loaded_after(modules: list) -> list:
    """Return the modules of :data:`EXTRA_MODULES` loaded by importing ``modules`` afresh."""
    script = ('import importlib, sys\n'
              f'for name in {modules!r}:\n'
              '    importlib.import_module(name)\n'
              'print("loaded:", sorted({n.split(".")[0] for n in sys.modules} & '
              f'{set(EXTRA_MODULES)!r}))')
    done = subprocess.run([sys.executable, '-c', script], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    # pybullet prints its banner on the same stdout, before or after.
    line = next(text for text in done.stdout.splitlines() if text.startswith('loaded: '))
    return ast.literal_eval(line.removeprefix('loaded: '))


@pytest.mark.sources
def test_the_nodes_import_no_package_of_an_extra():
    assert loaded_after(NODES) == []


@pytest.mark.sources
def test_the_commands_import_no_package_of_an_extra_until_a_feature_needs_it():
    assert len(COMMANDS) >= 12
    assert loaded_after(COMMANDS) == []
    # The check itself: a module of a feature loads its extra.
    assert {'optuna', 'sqlalchemy'} <= set(loaded_after(['nfmr_dlsmc.analysis.chassis_tuning']))


def setup_requirements() -> tuple:
    """Return setup.py's ``install_requires`` and ``extras_require``, read without running it."""
    tree = ast.parse((ROOT / 'setup.py').read_text())
    call = next(node for node in ast.walk(tree) if isinstance(node, ast.Call)
                and getattr(node.func, 'id', None) == 'setup')
    keywords = {keyword.arg: keyword.value for keyword in call.keywords}
    return (ast.literal_eval(keywords['install_requires']),
            ast.literal_eval(keywords['extras_require']))


def names(requirements) -> set:
    return {canonicalize_name(Requirement(text).name) for text in requirements}


@pytest.mark.sources
def test_install_requires_holds_no_package_of_an_extra_and_each_extra_its_own():
    install_requires, extras_require = setup_requirements()
    distributions = {extra: {canonicalize_name(d) for d in modules.values()}
                     for extra, modules in EXTRAS.items()}
    assert names(install_requires) & set().union(*distributions.values()) == set()
    assert {extra: names(extras_require[extra]) for extra in EXTRAS} == distributions
    # The suite tests every feature: the test extra takes the others.
    ours = [Requirement(text) for text in extras_require['test']
            if canonicalize_name(Requirement(text).name) == 'nfmr-dlsmc']
    assert [set(r.extras) for r in ours] == [set(EXTRAS)]


def installed_with(requirements) -> set:
    """Return the distributions ``requirements`` install, as this environment's metadata says."""
    found, todo = set(), [Requirement(text) for text in requirements]
    while todo:
        requirement = todo.pop()
        name = canonicalize_name(requirement.name)
        if name in found:
            continue
        found.add(name)
        for text in metadata.distribution(name).requires or []:
            needed = Requirement(text)
            if needed.marker is None or needed.marker.evaluate({'extra': ''}):
                todo.append(needed)
    return found


def third_party_imports() -> set:
    """Return the top-level modules outside the standard library the package imports."""
    found = set()
    for path in [*(ROOT / 'nfmr_dlsmc').rglob('*.py'), *(ROOT / 'nfmr_sim').rglob('*.py')]:
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                found |= {alias.name.split('.')[0] for alias in node.names}
            elif isinstance(node, ast.ImportFrom):
                found.add(node.module.split('.')[0])
    return found - set(sys.stdlib_module_names) - {'nfmr_dlsmc', 'nfmr_sim'}


@pytest.mark.sources
def test_every_module_the_package_imports_comes_with_the_nodes_or_with_an_extra():
    install_requires, _ = setup_requirements()
    base = installed_with(install_requires)
    providers = metadata.packages_distributions()

    def with_the_nodes(module):
        return bool({canonicalize_name(d) for d in providers.get(module, [])} & base)

    imported = third_party_imports()
    of_extras = set(EXTRA_MODULES) - {'dask'}
    assert {m for m in imported if not with_the_nodes(m)} == of_extras
    assert of_extras <= imported  # an extra nothing imports would be installed for nothing
    assert not any(with_the_nodes(m) for m in EXTRA_MODULES)


def test_missing_names_the_packages_not_installed_and_the_extras_that_install_them(
        monkeypatch):
    assert missing('plots', 'tune', 'cluster') == ''
    require('--anything', 'plots', 'tune', 'cluster')
    monkeypatch.setitem(sys.modules, 'PIL', None)
    assert missing('plots', 'cluster') == (
        "pillow, which is not installed: pip install 'nfmr_dlsmc[plots]'")
    monkeypatch.setitem(sys.modules, 'optuna', None)
    monkeypatch.setitem(sys.modules, 'sqlalchemy', None)
    with pytest.raises(MissingExtra) as refused:
        require('--plant pybullet', 'tune', 'plots')
    assert str(refused.value) == (
        '--plant pybullet needs optuna, sqlalchemy and pillow, which are not installed: '
        "pip install 'nfmr_dlsmc[tune,plots]'")


def test_nfmr_runs_report_without_plots_says_once_why_and_reports_the_rest(
        tmp_path, monkeypatch, capsys):
    params = controller_params({})
    run = simulate(DlsmcController(params.dlsmc), params.trajectory, (1.0, 4.0, 0.0), 3.0)
    written = write_run_bag(tmp_path / 'bag', run, every=10)
    options = RunOptions(config=None, mode='lockstep', duration=3.0, out=tmp_path,
                         no_record=False, gui=False, hold_from=1.0, stall_timeout=30.0,
                         no_compare=True)
    monkeypatch.setitem(sys.modules, 'matplotlib', None)
    report_run(tmp_path / 'bag', tmp_path, params, None, options,
               {'/controller_state': len(written)}, 1.0)
    out, err = capsys.readouterr()
    assert err.splitlines() == [
        'nfmr-run: note: no plots: drawing them needs matplotlib, which is not installed: '
        "pip install 'nfmr_dlsmc[plots]'"]
    assert 'IAE of distance' in out and '300 control ticks' in out and 'plots' not in out
    assert sorted(p.name for p in tmp_path.iterdir()) == ['bag', 'timing.json']


#: What pybullet itself prints when it is imported; not ours.
PYBULLET_LINES = ('pybullet build time', 'argv[0]=')
ROBOT = str(ROOT / 'config' / 'robot_case1.yaml')
#: (package made missing, command module, its arguments given the test's folder, the line).
MISSING = [
    pytest.param('matplotlib', 'compare', lambda d: ['--out', str(d / 'report')],
                 "nfmr-compare: error: drawing the report's figures needs matplotlib, which is "
                 "not installed: pip install 'nfmr_dlsmc[plots]'", id='compare'),
    pytest.param('PIL', 'montecarlo', lambda d: ['--n', '2', '--plots', str(d / 'plots')],
                 'nfmr-montecarlo: error: --plots needs pillow, which is not installed: '
                 "pip install 'nfmr_dlsmc[plots]'", id='montecarlo-plots'),
    pytest.param('distributed', 'montecarlo',
                 lambda d: ['--n', '2', '--params', ROBOT, '--duration', '1',
                            '--scheduler', 'tcp://127.0.0.1:8786'],
                 'nfmr-montecarlo: error: --scheduler needs distributed, which is not '
                 "installed: pip install 'nfmr_dlsmc[cluster]'", id='montecarlo-scheduler'),
    pytest.param('matplotlib', 'analyze',
                 lambda d: [str(d / 'bag'), '--animate', str(d / 'run.gif')],
                 'nfmr-analyze: error: --animate needs matplotlib, which is not installed: '
                 "pip install 'nfmr_dlsmc[plots]'", id='analyze-animate'),
    pytest.param('matplotlib', 'analyze',
                 lambda d: [str(d / 'bag'), '--plots', str(d / 'plots')],
                 'nfmr-analyze: error: --plots needs matplotlib, which is not installed: '
                 "pip install 'nfmr_dlsmc[plots]'", id='analyze-plots'),
    pytest.param('matplotlib', 'run', lambda d: ['--animate', '--out', str(d / 'runs')],
                 'nfmr-run: error: --animate needs matplotlib, which is not installed: '
                 "pip install 'nfmr_dlsmc[plots]'", id='run-animate'),
    # Refused before the chassis is built: the study's plant is only named.
    pytest.param('optuna', 'tune',
                 lambda d: ['--plant', 'pybullet', '--out', str(d / 'tuned.yaml')],
                 'nfmr-tune: error: --plant pybullet needs optuna, which is not installed: '
                 "pip install 'nfmr_dlsmc[tune]'", id='tune-pybullet'),
]


@pytest.mark.commands
@pytest.mark.sim
@pytest.mark.parametrize('package, command, args, line', MISSING)
def test_a_feature_without_its_extra_ends_with_one_line_naming_the_extra(
        tmp_path, package, command, args, line):
    script = (f'import sys\nsys.modules[{package!r}] = None\n'
              f'from nfmr_dlsmc.cli.{command} import main\n'
              f'sys.exit(main({args(tmp_path)!r}))\n')
    done = subprocess.run([sys.executable, '-c', script], capture_output=True, text=True,
                          timeout=120, cwd=tmp_path)
    errors = [text for text in done.stderr.splitlines() if not text.startswith(PYBULLET_LINES)]
    assert (done.returncode, errors) == (2, [line])
    assert list(tmp_path.iterdir()) == []  # before any work
