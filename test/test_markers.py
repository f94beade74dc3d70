"""
Every test that spins ROS, steps pybullet or starts nfmr's commands carries the marker saying so.

The markers (``ros``, ``sim``, ``commands``; setup.cfg) are what keeps these tests out of
``make mutate`` (doc/mutation.md): without its marker, such a test lands in the mutation run
unnoticed. What a test does is read from its source: the names it uses, followed through the
helpers and fixtures of its module and the test/ modules it imports them from.

- ``ros``: it uses rclpy (but for ``rclpy.serialization``, plain CDR bytes), constructs one of
  the package's nodes, or hands a child Python a script that starts rclpy;
- ``sim``: it uses pybullet, the chassis world, the pybullet plant or the sim node, or passes
  ``pybullet`` as a plant (an argument, or after ``--plant``);
- ``commands``: it starts a process (``subprocess``) and names one of nfmr's commands
  (``nfmr-...``) or runs one of its modules with ``-m``.
"""

import ast
from pathlib import Path
import re

import pytest

pytestmark = pytest.mark.sources

HERE = Path(__file__).parent
SPAWNS = {'run', 'Popen', 'call', 'check_call', 'check_output'}
COMMAND = re.compile(r'nfmr-[a-z]+(-[a-z]+)*')
STARTS_RCLPY = re.compile(r'\brclpy\.(init|create_node)\b')


def _marks(decorators):
    """Return the names of the ``pytest.mark.NAME`` among ``decorators`` (nodes)."""
    names = set()
    for node in decorators:
        node = node.func if isinstance(node, ast.Call) else node
        if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Attribute)
                and node.value.attr == 'mark'):
            names.add(node.attr)
    return names


def _is_fixture(node):
    return any('fixture' in ast.unparse(d) for d in node.decorator_list)


class Module:
    """One test module, parsed: its definitions, its imports and its markers."""

    _cache = {}

    def __init__(self, name, source):
        self.name = name
        self.tree = ast.parse(source)
        self.defs = {}  # module-level name -> the statement defining it
        self.imports = {}  # a name bound by an import anywhere -> (module, attribute or None)
        self.on_import = []  # statements run on import that define nothing
        self.marks = set()
        for node in ast.walk(self.tree):
            if isinstance(node, ast.Import):
                for alias in node.names:
                    bound = alias.asname or alias.name.split('.')[0]
                    self.imports[bound] = (alias.name if alias.asname else bound, None)
            elif isinstance(node, ast.ImportFrom) and node.level == 0:
                for alias in node.names:
                    self.imports[alias.asname or alias.name] = (node.module, alias.name)
        for node in self.tree.body:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                self.defs[node.name] = node
            elif isinstance(node, (ast.Assign, ast.AnnAssign)):
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                for target in targets:
                    for name in ast.walk(target):
                        if isinstance(name, ast.Name):
                            self.defs[name.id] = node
                if any(isinstance(t, ast.Name) and t.id == 'pytestmark' for t in targets):
                    values = node.value.elts if isinstance(
                        node.value, (ast.List, ast.Tuple)) else [node.value]
                    self.marks |= _marks(values)
            elif not isinstance(node, (ast.Import, ast.ImportFrom, ast.Expr)) or (
                    isinstance(node, ast.Expr) and not isinstance(node.value, ast.Constant)):
                self.on_import.append(node)

    @classmethod
    def named(cls, name):
        """Return the module ``name`` of test/, parsed once."""
        if name not in cls._cache:
            cls._cache[name] = cls(name, (HERE / f'{name}.py').read_text())
        return cls._cache[name]

    def tests(self):
        """Yield (test name, its node, the markers it carries) for each test of the module."""
        for node in self.tree.body:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and \
                    node.name.startswith('test'):
                yield node.name, node, self.marks | _marks(node.decorator_list)
            elif isinstance(node, ast.ClassDef) and node.name.startswith('Test'):
                for method in node.body:
                    if isinstance(method, ast.FunctionDef) and method.name.startswith('test'):
                        yield (f'{node.name}::{method.name}', method, self.marks
                               | _marks(node.decorator_list) | _marks(method.decorator_list))

    def facts(self, node, seen=None):
        """
        Return what running ``node`` does, as {fact: the first name that shows it}.

        Facts: ``ros``, ``sim``, ``spawn`` (starts a process) and ``command`` (names one of
        nfmr's commands or modules); the names ``node`` uses are followed into the module's
        definitions and into the test/ modules they come from.
        """
        seen = set() if seen is None else seen
        found = {}

        def add(fact, why):
            found.setdefault(fact, why)

        def follow(name):
            if name in self.defs and (self.name, name) not in seen:
                seen.add((self.name, name))
                for fact, why in self.facts(self.defs[name], seen).items():
                    add(fact, why)

        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and (
                node.name.startswith('test') or _is_fixture(node)):
            for arg in node.args.args:  # fixtures by name: the module's, then conftest's
                if arg.arg in self.defs:
                    follow(arg.arg)
                elif self.name != 'conftest' and arg.arg in Module.named('conftest').defs:
                    for fact, why in Module.named('conftest').facts(
                            Module.named('conftest').defs[arg.arg], seen).items():
                        add(fact, why)
        for sub in ast.walk(node):
            if isinstance(sub, ast.Name):
                if sub.id in self.imports:
                    for fact, why in self._imported(*self.imports[sub.id], seen).items():
                        add(fact, why)
                else:
                    follow(sub.id)
            elif isinstance(sub, ast.Attribute) and sub.attr in SPAWNS and isinstance(
                    sub.value, ast.Name) and self.imports.get(sub.value.id) == (
                        'subprocess', None):
                add('spawn', f'subprocess.{sub.attr}')
            elif isinstance(sub, ast.Constant) and isinstance(sub.value, str):
                if COMMAND.fullmatch(sub.value):
                    add('command', repr(sub.value))
                if STARTS_RCLPY.search(sub.value):
                    add('ros', 'a script that starts rclpy')
            if isinstance(sub, ast.Call):
                args = sub.args + [k.value for k in sub.keywords]
                if any(isinstance(a, ast.Constant) and a.value == 'pybullet' for a in args):
                    add('sim', "the 'pybullet' plant")
                if isinstance(sub.func, ast.Attribute) and sub.func.attr.endswith('Node'):
                    add('ros', ast.unparse(sub.func))  # a node of a module: module.SomeNode()
            if isinstance(sub, (ast.List, ast.Tuple, ast.Call)):
                items = sub.args if isinstance(sub, ast.Call) else sub.elts
                values = [i.value if isinstance(i, ast.Constant) else None for i in items]
                for before, value in zip(values, values[1:]):
                    if before == '--plant' and value == 'pybullet':
                        add('sim', "'--plant pybullet'")
                    if before == '-m' and isinstance(value, str) and value.startswith('nfmr_'):
                        add('command', f'-m {value}')
        return found

    def _imported(self, module, attribute, seen):
        """Return the facts of using ``attribute`` of ``module`` (all of it for None)."""
        top = module.split('.')[0]
        if module == 'subprocess' and attribute in SPAWNS:
            return {'spawn': f'subprocess.{attribute}'}
        if top == 'rclpy' and not module.startswith('rclpy.serialization'):
            return {'ros': module if attribute is None else f'{module}.{attribute}'}
        if top in ('pybullet', 'pybullet_data', 'pybullet_utils') or module.startswith(
                'nfmr_sim.plant') or attribute in ('ChassisWorld', 'SimNode'):
            facts = {'sim': f'{module}.{attribute}'}
            if attribute == 'SimNode':
                facts['ros'] = f'{module}.{attribute}'
            return facts
        if top in ('nfmr_dlsmc', 'nfmr_sim') and '.ros' in module and attribute and \
                attribute.endswith('Node'):
            return {'ros': f'{module}.{attribute}'}
        if attribute is not None and (HERE / f'{module}.py').is_file():
            other = Module.named(module)
            if (module, attribute) not in seen and attribute in other.defs:
                seen.add((module, attribute))
                return {fact: f'{module}.{attribute} uses {why}' for fact, why in
                        other.facts(other.defs[attribute], seen).items()}
        return {}

    def missing(self):
        """Return a line for each test that does what a marker says without carrying it."""
        on_import = {}
        for node in self.on_import:
            on_import.update(self.facts(node))
        autouse = [n for n in self.tree.body if isinstance(n, ast.FunctionDef) and any(
            'autouse=True' in ast.unparse(d) for d in n.decorator_list)]
        lines = []
        for name, node, marks in self.tests():
            facts = dict(on_import)
            for fixture in autouse:
                facts.update(self.facts(fixture))
            facts.update(self.facts(node))
            needs = {m: facts[m] for m in ('ros', 'sim') if m in facts}
            if 'spawn' in facts and 'command' in facts:
                needs['commands'] = f"{facts['spawn']} of {facts['command']}"
            lines += [f'{self.name}.py::{name}: {marker} ({why}) not marked'
                      for marker, why in sorted(needs.items()) if marker not in marks]
        return lines


@pytest.mark.parametrize('path', sorted(HERE.glob('test_*.py')), ids=lambda p: p.name)
def test_every_test_that_spins_ros_steps_pybullet_or_runs_commands_is_marked(path):
    assert Module.named(path.stem).missing() == []


UNMARKED = """
import subprocess
import sys
from pathlib import Path

from nfmr_dlsmc.analysis.evaluation import load_evaluation
from nfmr_dlsmc.ros.controller_node import ControllerNode
import pytest
from ros_helpers import new_context, wait_for

EVAL = str(Path(sys.executable).parent / 'nfmr-eval')


@pytest.fixture
def node():
    return ControllerNode(context=new_context())


def run(*args):
    return subprocess.run([EVAL, *args])


def test_spins(node):
    wait_for(lambda: True)


def test_steps():
    load_evaluation('pybullet', 'dlsmc')


def test_runs():
    run('--plant', 'kinematic')


@pytest.mark.commands
def test_runs_marked():
    run('--help')


def test_plain():
    wait_for(lambda: True)
    subprocess.run(['true'])
"""


def test_the_check_names_each_unmarked_test_and_what_it_does():
    assert Module('unmarked', UNMARKED).missing() == [
        'unmarked.py::test_spins: ros (nfmr_dlsmc.ros.controller_node.ControllerNode) not marked',
        "unmarked.py::test_steps: sim (the 'pybullet' plant) not marked",
        "unmarked.py::test_runs: commands (subprocess.run of 'nfmr-eval') not marked",
    ]
    marked = UNMARKED.replace('import pytest\n', 'import pytest\n\npytestmark = [\n'
                              '    pytest.mark.ros, pytest.mark.sim, pytest.mark.commands]\n')
    assert Module('marked', marked).missing() == []
