"""
The layer map of doc/design.md, checked on the sources.

Each module of ``nfmr_dlsmc`` and ``nfmr_sim`` belongs to a layer (its sub-package); a
layer imports only from the layers below it; ``nfmr_dlsmc`` never imports ``nfmr_sim``
(the simulator registers itself as a plant instead); rclpy, pybullet, matplotlib and mcap
are imported only where the map allows, and the core imports with them blocked; the ROS
layers import with matplotlib blocked (they draw, at the end of a run, only when they do).
The laws (core, baselines, plants) never import the benchmark's plain loop, and saturate
their inputs and wrap angles only through core/saturation.py and core/angles.py.
"""

import ast
from pathlib import Path
import subprocess
import sys

import pytest

pytestmark = pytest.mark.sources

ROOT = Path(__file__).resolve().parents[1]

#: nfmr_dlsmc's layers, bottom first: a layer may import its own and those before it.
DLSMC_LAYERS = ('core', 'baselines', 'plants', 'runtime', 'bag', 'analysis', 'ros', 'cli')
#: Where nfmr_sim's two parts sit on that ladder: the ROS-free world just above
#: nfmr_dlsmc's runtime, its node just above nfmr_dlsmc's ros layer.
SIM_LAYERS = {'world': 3.5, 'ros': 6.5}
#: The package's own __init__ (the public API) re-exports from core, plants and runtime.
API_RANK = 3.25

#: Third-party packages each layer may import (the standard library is always allowed).
THIRD_PARTY = {
    'core': {'numpy', 'scipy'},
    'baselines': {'numpy', 'yaml'},
    'plants': {'numpy', 'scipy'},
    'runtime': {'numpy', 'yaml', 'ament_index_python', 'distributed'},
    'bag': {'numpy', 'yaml', 'mcap', 'zstandard'},
    'analysis': {'numpy', 'yaml', 'matplotlib', 'PIL', 'optuna', 'sqlalchemy'},
    'ros': {'numpy', 'yaml', 'rclpy', 'builtin_interfaces', 'geometry_msgs',
            'nav_msgs', 'sensor_msgs', 'std_msgs', 'rosgraph_msgs', 'diagnostic_msgs',
            'rcl_interfaces', 'lifecycle_msgs', 'std_srvs', 'visualization_msgs'},
    'cli': {'numpy', 'yaml', 'matplotlib'},
    'api': set(),
    'sim.world': {'numpy', 'pybullet', 'pybullet_utils', 'matplotlib'},
}
THIRD_PARTY['sim.ros'] = THIRD_PARTY['ros'] | {'numpy'}


def _modules():
    """(dotted name, path) of every module of both packages."""
    for package in ('nfmr_dlsmc', 'nfmr_sim'):
        for path in sorted((ROOT / package).rglob('*.py')):
            parts = path.relative_to(ROOT).with_suffix('').parts
            if parts[-1] == '__init__':
                parts = parts[:-1]
            yield '.'.join(parts), path


def layer_of(module: str) -> str:
    """Return the layer a module belongs to; AssertionError for one outside the map."""
    parts = module.split('.')
    if parts[0] == 'nfmr_dlsmc':
        if len(parts) == 1:
            return 'api'
        assert parts[1] in DLSMC_LAYERS, f'{module} is in no layer'
        return parts[1]
    assert parts[0] == 'nfmr_sim', module
    if len(parts) > 1 and parts[1] == 'ros':
        return 'sim.ros'
    return 'sim.world'


def rank(layer: str) -> float:
    if layer == 'api':
        return API_RANK
    if layer.startswith('sim.'):
        return SIM_LAYERS[layer[4:]]
    return float(DLSMC_LAYERS.index(layer))


def imports_of(path: Path):
    """Absolute module names imported anywhere in a file (function bodies included)."""
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name
        elif isinstance(node, ast.ImportFrom):
            assert node.level == 0, f'{path}:{node.lineno}: relative import'
            yield node.lineno, node.module


MODULES = dict(_modules())
STDLIB = sys.stdlib_module_names


def test_every_module_belongs_to_a_layer():
    outside = []
    for module in MODULES:
        try:
            layer_of(module)
        except AssertionError as exc:
            outside.append(str(exc))
    assert outside == []
    assert {layer_of(m) for m in MODULES} == {*DLSMC_LAYERS, 'api', 'sim.world', 'sim.ros'}


@pytest.mark.parametrize('module', sorted(MODULES))
def test_imports_go_only_downward(module):
    layer = layer_of(module)
    wrong = []
    for line, imported in imports_of(MODULES[module]):
        top = imported.split('.')[0]
        where = f'{MODULES[module].relative_to(ROOT)}:{line}'
        if top in ('nfmr_dlsmc', 'nfmr_sim'):
            if module.startswith('nfmr_dlsmc') and top == 'nfmr_sim':
                wrong.append(f'{where}: imports {imported}; nfmr_dlsmc must not import nfmr_sim')
            elif rank(layer_of(imported)) > rank(layer):
                wrong.append(f'{where}: {layer} imports {imported} of layer '
                             f'{layer_of(imported)}, which is above it')
        elif top not in STDLIB and top not in THIRD_PARTY[layer]:
            wrong.append(f'{where}: {layer} may not import {imported}')
    assert wrong == []


def import_blocked(modules: list, blocked: set) -> subprocess.CompletedProcess:
    """Import ``modules`` in a fresh interpreter in which ``blocked`` and its submodules fail."""
    script = (
        'import importlib, sys\n'
        'class Block:\n'
        '    def find_spec(self, name, path=None, target=None):\n'
        f'        if any(name == b or name.startswith(b + ".") for b in {sorted(blocked)!r}):\n'
        '            raise ImportError(f"blocked: {name}")\n'
        'sys.meta_path.insert(0, Block())\n'
        f'for name in {modules!r}:\n'
        '    importlib.import_module(name)\n'
        'print(len(sys.modules))\n')
    return subprocess.run([sys.executable, '-c', script], capture_output=True, text=True,
                          timeout=120)


def test_the_core_imports_with_ros_pybullet_matplotlib_and_mcap_blocked():
    core = [m for m in MODULES if layer_of(m) == 'core']
    done = import_blocked(core, {'rclpy', 'pybullet', 'matplotlib', 'mcap'})
    assert done.returncode == 0, done.stderr
    assert len(core) >= 10


def test_the_ros_layers_import_without_matplotlib():
    """The nodes and the launcher start without it; the end-of-run report draws with it."""
    ros = [m for m in MODULES if layer_of(m) in ('ros', 'sim.ros')]
    done = import_blocked(ros, {'matplotlib'})
    assert done.returncode == 0, done.stderr
    assert 'nfmr_dlsmc.ros.launcher' in ros and 'nfmr_sim.ros.sim_node' in ros


def test_a_blocked_import_is_caught_through_the_modules_between():
    """The check itself: analysis' animation imports matplotlib, so a module importing it fails."""
    done = import_blocked(['nfmr_dlsmc.analysis.animation'], {'matplotlib'})
    assert done.returncode != 0 and 'blocked: matplotlib' in done.stderr


def test_the_layer_test_catches_an_upward_import(tmp_path):
    """The check itself: an upward import and a forbidden package are reported."""
    bad = tmp_path / 'bad.py'
    bad.write_text('import rclpy\nfrom nfmr_dlsmc.cli.eval import main\n')
    found = list(imports_of(bad))
    assert found == [(1, 'rclpy'), (2, 'nfmr_dlsmc.cli.eval')]
    assert rank(layer_of('nfmr_dlsmc.cli.eval')) > rank(layer_of('nfmr_dlsmc.core.dlsmc'))
    assert 'rclpy' not in THIRD_PARTY['core']


#: The layers of the control laws, the comparison laws and the models they drive.
LAW_LAYERS = ('core', 'baselines', 'plants')
#: The plain loop of nfmr-bench, the laws written out again on purpose as its yardstick.
PLAIN_LOOP = 'nfmr_dlsmc.analysis.plain_loop'


def _parents(module: str) -> list:
    """Return ``module`` and the packages whose ``__init__`` runs when it is imported."""
    parts = module.split('.')
    return ['.'.join(parts[:k]) for k in range(1, len(parts) + 1)]


def modules_imported_by(path: Path) -> set:
    """Return the modules of both packages a file imports, with the packages they sit in."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            named = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            named = [node.module, *(f'{node.module}.{alias.name}' for alias in node.names)]
        else:
            continue
        found.update(p for name in named for p in _parents(name) if p in MODULES)
    return found


def import_closure(module: str) -> set:
    """Return every module of both packages that importing ``module`` may import, at any depth."""
    seen, todo = set(), _parents(module)
    while todo:
        name = todo.pop()
        if name in seen or name not in MODULES:
            continue
        seen.add(name)
        todo.extend(modules_imported_by(MODULES[name]))
    return seen


def test_the_plain_loop_is_only_the_benchmarks_yardstick():
    """No law imports it, at any depth (issue 39): each equation runs from its one function."""
    laws = [m for m in MODULES if layer_of(m) in LAW_LAYERS]
    reaching = sorted(m for m in laws if PLAIN_LOOP in import_closure(m))
    assert reaching == []
    assert {m for m in MODULES if PLAIN_LOOP in modules_imported_by(MODULES[m])} == {
        'nfmr_dlsmc.analysis.benchmarks'}
    # The check itself: the benchmarks reach it, and so does the command that runs them.
    assert PLAIN_LOOP in import_closure('nfmr_dlsmc.cli.bench')
    # And at import time, through whatever importlib does, in a fresh interpreter.
    done = import_blocked(laws, {PLAIN_LOOP})
    assert done.returncode == 0, done.stderr


#: The input limits (InputLimits' fields): bounds of the input saturation.
INPUT_LIMITS = {'v_min', 'v_max', 'omega_max'}
#: Functions that clip a value to bounds.
CLAMPS = {'min', 'max', 'clip', 'minimum', 'maximum'}
#: The one module that writes the input saturation, and the one that writes the wrap.
SATURATION, ANGLES = 'nfmr_dlsmc.core.saturation', 'nfmr_dlsmc.core.angles'


def _is_limit(node) -> bool:
    """Whether an expression is an input limit or its negation (``-limits.omega_max``)."""
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
        node = node.operand
    return (isinstance(node, ast.Name) and node.id in INPUT_LIMITS
            or isinstance(node, ast.Attribute) and node.attr in INPUT_LIMITS)


def _compares_with_a_limit(test) -> bool:
    return isinstance(test, ast.Compare) and any(
        _is_limit(o) for o in (test.left, *test.comparators))


def _called(node) -> str | None:
    """Return the name of the function a call calls (``np.clip`` -> ``clip``)."""
    func = node.func
    return func.id if isinstance(func, ast.Name) else getattr(func, 'attr', None)


def inline_saturations(source: str) -> list:
    """
    Return (line, what) of each input saturation written out in ``source``.

    An input limit as a bound of min, max or a clip; a conditional expression that compares
    with one and yields it (``v_min if v < v_min else ...``); an ``if`` that compares with
    one and assigns it (``if v > v_max: v = v_max``). A limit inside arithmetic (the path
    profile's omega_max / kappa, the turn-first cap v_min / sin) is not a bound.
    """
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Call) and _called(node) in CLAMPS and any(
                _is_limit(a) for a in node.args):
            found.append((node.lineno, f'{_called(node)}() with an input limit'))
        elif isinstance(node, ast.IfExp) and _compares_with_a_limit(node.test) and (
                _is_limit(node.body) or _is_limit(node.orelse)):
            found.append((node.lineno, 'conditional expression'))
        elif isinstance(node, ast.If) and _compares_with_a_limit(node.test) and any(
                isinstance(s, ast.Assign) and _is_limit(s.value) for s in node.body):
            found.append((node.lineno, 'if statement'))
    return found


def _wraps(source: str) -> list:
    """Return the lines that call a remainder: the wrap of an angle written out."""
    return [node.lineno for node in ast.walk(ast.parse(source))
            if isinstance(node, ast.Call) and _called(node) == 'remainder']


@pytest.mark.parametrize('module', sorted(m for m in MODULES if layer_of(m) in LAW_LAYERS))
def test_the_laws_saturate_and_wrap_through_the_one_function(module):
    """Input saturation only in core/saturation.py, the wrap only in core/angles.py."""
    source = MODULES[module].read_text()
    if module != SATURATION:
        assert inline_saturations(source) == []
    if module != ANGLES:
        assert _wraps(source) == []


def test_the_saturation_check_finds_what_was_written_out():
    """The check itself, on the forms the laws and the batch had before issue 39."""
    written_out = (
        'v = v_min if v_want < v_min else (limits.v_max if v_want > limits.v_max else v_want)\n'
        'w = limits.omega_max if w > limits.omega_max else (\n'
        '    -limits.omega_max if w < -limits.omega_max else w)\n'
        'driven = min(max(v, self.speed_floor(ref.v_r)), self._limits.v_max)\n'
        'omega = min(max(curvature * v, -omega_max), omega_max)\n'
        'v = np.clip(np.hypot(u_x, u_y), lim.v_min, lim.v_max)\n'
        'if v > limits.v_max:\n'
        '    v_sat = limits.v_max\n'
        's = math.remainder(theta - theta_d, 2.0 * math.pi)\n')
    lines = sorted(line for line, _ in inline_saturations(written_out))
    assert lines == [1, 1, 2, 3, 4, 5, 5, 6, 7]
    assert _wraps(written_out) == [9]
    legitimate = ('limit = np.minimum(a / bend, (profile.omega_max / bend) ** 2)\n'
                  'if v_want * across > limits.v_min:\n'
                  '    v_want = limits.v_min / across\n'
                  'held = (abs(w) > lim.omega_max) if anti_windup else False\n'
                  'kappa = min(max(kappa, -reach), reach)\n')
    assert inline_saturations(legitimate) == []


#: The rosdep key of each third-party import that is not a ROS package of the same name.
ROSDEP_KEYS = {'numpy': 'python3-numpy', 'scipy': 'python3-scipy', 'yaml': 'python3-yaml',
               'matplotlib': 'python3-matplotlib', 'PIL': 'python3-pil',
               'pybullet': 'python3-pybullet-pip', 'pybullet_utils': 'python3-pybullet-pip',
               'mcap': 'python3-mcap-pip', 'zstandard': 'python3-zstandard',
               'optuna': 'python3-optuna-pip', 'sqlalchemy': 'python3-sqlalchemy',
               'distributed': 'python3-distributed'}


def test_package_xml_lists_every_dependency_the_code_may_import():
    import xml.etree.ElementTree as ElementTree

    manifest = ElementTree.parse(ROOT / 'package.xml').getroot()
    listed = {e.text for e in manifest if e.tag in ('depend', 'exec_depend')}
    needed = {ROSDEP_KEYS.get(name, name) for names in THIRD_PARTY.values() for name in names}
    assert needed - listed == set()
    assert listed - needed == set()  # and nothing the code does not import


#: Cyclomatic complexity allowed in the functions of the 1 kHz step (radon's measure).
STEP_FUNCTIONS = {'nfmr_dlsmc/runtime/tracking_session.py': ('tick', 'on_odometry'),
                  'nfmr_dlsmc/runtime/odometry_gate.py': ('offer',)}


@pytest.mark.parametrize('path, names', STEP_FUNCTIONS.items())
def test_the_control_step_reads_in_one_go(path, names):
    from radon.complexity import cc_visit

    blocks = {b.name: b.complexity for b in cc_visit((ROOT / path).read_text())
              for b in [b, *getattr(b, 'methods', [])]}
    assert {n: blocks[n] for n in names if blocks[n] > 12} == {}
