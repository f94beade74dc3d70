"""
The measured figures the documentation quotes, each with the command that measures it.

``make results`` measures :data:`FIGURES` and writes doc/results.md (:func:`render`): one
row a figure, with its value as the docs quote it, its unit, what it is, what measured it
and when. A figure comes from a command of this package (``nfmr-eval ... --json`` and a
key of its JSON object), from pytest's collection (how many tests ``make test`` runs), or
from a count of the source tree (:data:`TREE_COUNTS`).

README.md and doc/*.md quote a figure as its value, its unit after it where they like, and
then the marker ``<!-- results:NAME -->`` (:func:`quotes`), which a rendered page does not
show; test/test_results_file.py fails when a quote differs from the file or a count of the
tree from the file's.

``python -m nfmr_dlsmc.analysis.results_file OUT.md [NAME ...]``, from the repository's
root: with names, only those figures are measured again, the others kept as OUT.md has them.
"""

import ast
from dataclasses import dataclass
import datetime
import json
from pathlib import Path
import re
import shlex
import shutil
import subprocess
import sys
import sysconfig
import time
from typing import NamedTuple

from nfmr_dlsmc.analysis.evaluation import PAPER_CASE1
from nfmr_dlsmc.runtime.params import controller_params, load_params_file

__all__ = ['FIGURES', 'Figure', 'Row', 'TREE_COUNTS', 'count_design_records',
           'count_robot_options', 'count_test_functions', 'main', 'measure', 'parse',
           'quotes', 'render', 'row_of']

#: The shipped robot profile, whose options ``robot_options`` counts.
ROBOT_PROFILE = 'config/robot_case1.yaml'
#: A design record's heading in doc/design.md: ``**D12 — the title.**``.
DESIGN_RECORD = re.compile(r'^\*\*D([0-9]+) —', re.M)
#: A quote in the docs: a number, its unit or not, then the marker naming the figure.
QUOTE = re.compile(r'(?<![0-9.+-])(?P<number>[+-]?[0-9]+(?:\.[0-9]+)?(?:e[+-]?[0-9]+)?)'
                   r'(?:[ ]?(?P<unit>[^\s<0-9]+))?[ ]?<!-- results:(?P<name>[a-z0-9_]+) -->')
#: A marker, after a quote or not.
MARKER = re.compile(r'<!-- results:(?P<name>[a-z0-9_]+) -->')
#: pytest's summary of a collection: ``1610/1653 tests collected (43 deselected) in 9.5s``.
COLLECTED = re.compile(r'([0-9]+)(?:/[0-9]+)? tests? collected(?: \(([0-9]+) deselected\))?')


def count_design_records(root: Path) -> int:
    """Return how many design records (``**Dn —``) doc/design.md holds."""
    return len(DESIGN_RECORD.findall((root / 'doc' / 'design.md').read_text()))


def count_robot_options(root: Path) -> int:
    """Return how many robot-profile options the shipped robot profile turns on."""
    params = controller_params(load_params_file(root / ROBOT_PROFILE))
    return len(params.dlsmc.robot_options)


def count_test_functions(root: Path) -> int:
    """
    Return how many test functions test/test_*.py define, each counted once.

    pytest's functions (``test*``) at a module's top level and in its ``Test*`` classes:
    pytest collects a parametrised one once per parameter set, so its count of
    collected tests is larger; ``make test`` leaves out those marked slow.
    """
    count = 0
    for path in sorted((root / 'test').glob('test_*.py')):
        tree = ast.parse(path.read_text())
        bodies = [tree.body] + [node.body for node in tree.body
                                if isinstance(node, ast.ClassDef) and node.name.startswith('Test')]
        count += sum(isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))
                     and node.name.startswith('test') for body in bodies for node in body)
    return count


#: Counts of the source tree: key -> (what is counted, the count of a root).
TREE_COUNTS = {
    'design_records': ('records `**Dn —` in doc/design.md', count_design_records),
    'robot_options': (f'`DlsmcConfig.robot_options` on in {ROBOT_PROFILE}', count_robot_options),
    'test_functions': ('functions `test*` of test/test_*.py, parametrised or not (ast)',
                       count_test_functions),
}


@dataclass(frozen=True)
class Figure:
    """
    One figure: what measures it and how the docs write it.

    Attributes
    ----------
    name : str
        Its name in the docs' markers.
    what : str
        What it is, in a few words.
    command : str or None
        The command that measures it, run from the repository's root (``nfmr-eval ...
        --json`` or ``pytest --collect-only ...``); None for a count of the tree.
    key : str
        The key of the command's JSON object, ``collected`` or ``deselected`` of pytest's
        collection, or the key of :data:`TREE_COUNTS`.
    unit : str
        The unit it is quoted in ('' for a count).
    scale : float
        The quoted value per measured one (1e3: metres quoted in millimetres).
    spec : str
        Python's format spec of the quoted value.
    relative_to : float or None
        Given, the figure is the measured value's difference from it [%].

    """

    name: str
    what: str
    command: str | None
    key: str
    unit: str = ''
    scale: float = 1.0
    spec: str = 'd'
    relative_to: float | None = None

    @property
    def how(self) -> str:
        """Return what measures it, as the results file says."""
        if self.command is None:
            return TREE_COUNTS[self.key][0]
        return f'`{self.command}` → `{self.key}`'

    def quoted(self, measured) -> str:
        """Return the measured value as the docs quote it; — for None (does not apply)."""
        if measured is None:
            return '—'
        if self.relative_to is not None:
            measured = 100.0 * (measured / self.relative_to - 1.0)
        elif self.scale != 1.0:
            measured = self.scale * measured
        return f'{measured:{self.spec}}'


#: How the docs quote a key of ``nfmr-eval --json``: key -> (what, unit, scale, spec).
EVAL_KEYS = {
    'iae': ('IAE of distance', 'm·s', 1.0, '.2f'),
    't_conv_1cm': ('last time the distance exceeds 1 cm', 's', 1.0, '.2f'),
    't_conv': ('last time the distance exceeds 1 mm (convergence time)', 's', 1.0, '.2f'),
    'hold_distance_p99': ('distance p99 after 15 s', 'mm', 1e3, '#.3g'),
    'hold_theta_e_p99': (r'\|θe\| p99 after 15 s', 'mrad', 1e3, '#.3g'),
    'hold_omega_tv': ('ω total variation after 15 s', 'rad/s²', 1.0, '#.2g'),
    'hold_omega_saturated': ('ticks with ω at its limit after 15 s', '%', 100.0, '.0f'),
    'hold_steer_joint_rate_max': ('steer joint rate max after 15 s', 'rad/s', 1.0, '#.2g'),
}
#: The hold figures of a run (:data:`EVAL_KEYS`).
HOLD = ('hold_distance_p99', 'hold_theta_e_p99', 'hold_omega_tv', 'hold_omega_saturated')


def _eval_figures(prefix: str, command: str, what: str, keys, units=None) -> list[Figure]:
    """
    Return the figures ``keys`` of one ``nfmr-eval`` command, named ``prefix_key``.

    ``units`` (key -> (unit, scale, spec)) quotes a key otherwise than :data:`EVAL_KEYS`.
    """
    figures = []
    for key in keys:
        detail, unit, scale, spec = EVAL_KEYS[key]
        unit, scale, spec = (units or {}).get(key, (unit, scale, spec))
        figures.append(Figure(f'{prefix}_{key}', f'{what}: {detail}', command, key, unit,
                              scale, spec))
    return figures


def _paper_diff(name: str, command: str, what: str, key: str, detail: str) -> Figure:
    """Return the difference of ``key`` (``detail``) from the paper's Table 2 value [%]."""
    return Figure(name, f"{what}: {detail} against the paper's {PAPER_CASE1[key]:g}", command,
                  key, '%', spec='+.1f', relative_to=PAPER_CASE1[key])


_TABLE2 = 'nfmr-eval --json'
_TABLE2_WHAT = "the paper's law, kinematic model, Case 1, 100 s"
_PAPER_CHASSIS = 'nfmr-eval --plant pybullet --params config/paper_case1.yaml --json'
_PROFILE = f'nfmr-eval --params {ROBOT_PROFILE} --json'
_PROFILE_WHAT = 'the robot profile, kinematic model, Case 1, 100 s'
_CHASSIS = f'nfmr-eval --plant pybullet --params {ROBOT_PROFILE}'
_COLLECT = "pytest --collect-only -q -p no:cacheprovider -m 'not slow'"

#: Every figure of doc/results.md, in its order.
FIGURES = tuple(
    [figure for key, detail, unit in (('iae', 'IAE of distance', 'm·s'),
                                      ('ise', 'ISE of distance', 'm²·s'),
                                      ('std', 'STD of distance', 'm'),
                                      ('t_conv', 'convergence time (1 mm)', 's'))
     for figure in (Figure(f'table2_{key}', f'{_TABLE2_WHAT}: {detail}', _TABLE2, key, unit,
                           spec='.4f'),
                    _paper_diff(f'table2_{key}_diff', _TABLE2, _TABLE2_WHAT, key, detail))]
    + _eval_figures('paper_chassis', _PAPER_CHASSIS, "the paper's law on the chassis, Case 1, "
                    '100 s', HOLD, {'hold_distance_p99': ('cm', 100.0, '#.2g'),
                                    'hold_theta_e_p99': ('rad', 1.0, '#.2g')})
    + _eval_figures('profile_kinematic', _PROFILE, _PROFILE_WHAT,
                    ('iae', 't_conv_1cm', 't_conv') + HOLD)
    + [_paper_diff('profile_kinematic_iae_diff', _PROFILE, _PROFILE_WHAT, 'iae',
                   'IAE of distance')]
    + _eval_figures('profile_chassis', f'{_CHASSIS} --json', 'the robot profile on the '
                    'chassis, ideal odometry, Case 1, 100 s',
                    ('iae', 't_conv_1cm', 't_conv') + HOLD + ('hold_steer_joint_rate_max',))
    + _eval_figures('profile_good', f'{_CHASSIS} --sensing good --duration 40 --json',
                    "the robot profile on the chassis, 'good' odometry, Case 1, 40 s",
                    HOLD + ('hold_steer_joint_rate_max',))
    + _eval_figures('profile_harsh', 'nfmr-eval --plant pybullet --params '
                    'config/robot_harsh_case1.yaml --duration 40 --json',
                    "robot_harsh_case1.yaml on the chassis, the 'harsh' odometry it sets, "
                    'Case 1, 40 s', HOLD + ('hold_steer_joint_rate_max',))
    + [figure for name, what in (('small_robot', 'untuned'),
                                 ('small_robot_tuned', 'tuned by nfmr-tune --plant pybullet'))
       for figure in _eval_figures(
           name, f'nfmr-eval --plant pybullet --params config/{name}.yaml --sensing good '
           '--duration 40 --json', f'the robot profile on the smaller chassis of {name}.yaml '
           f"({what}), 'good' odometry, Case 1, 40 s", ('t_conv_1cm',) + HOLD[:2])]
    + [Figure('tests_collected', 'tests `make test` runs (pytest collects them)', _COLLECT,
              'collected'),
       Figure('tests_slow', 'tests marked slow, which `make test-all` adds', _COLLECT,
              'deselected'),
       Figure('test_functions', 'test functions of the suite, each counted once', None,
              'test_functions'),
       Figure('design_records', 'design records of doc/design.md (D1 to this)', None,
              'design_records'),
       Figure('robot_options', 'robot options the robot profile turns on', None,
              'robot_options')])


class Row(NamedTuple):
    """A row of the results file: a figure's name, quoted value, unit, what, how, date."""

    name: str
    value: str
    unit: str
    what: str
    how: str
    date: str


def row_of(figure: Figure, value: str, date: str) -> Row:
    """Return the row of ``figure`` measured as ``value`` on ``date``."""
    return Row(figure.name, value, figure.unit, figure.what, figure.how, date)


def _executable(word: str) -> str:
    """Return the path of a command, this environment's own first (its ``bin/``)."""
    found = shutil.which(word, path=sysconfig.get_path('scripts')) or shutil.which(word)
    if found is None:
        raise RuntimeError(f'{word}: not found in this environment (run make setup)')
    return found


def _collection(stdout: str) -> dict:
    """Return ``collected`` and ``deselected`` of pytest's collection summary."""
    found = COLLECTED.search(stdout)
    if found is None:
        raise RuntimeError(f'no collection summary in the output of pytest: {stdout[-300:]!r}')
    return {'collected': int(found.group(1)), 'deselected': int(found.group(2) or 0)}


def _run(command: str, root: Path) -> dict:
    """Run ``command`` in ``root`` and return what it measured, by key."""
    words = shlex.split(command)
    start = time.monotonic()
    done = subprocess.run([_executable(words[0])] + words[1:], cwd=root, capture_output=True,
                          text=True, check=False)
    print(f'{command}: {time.monotonic() - start:.1f} s', file=sys.stderr, flush=True)
    if done.returncode != 0:
        raise RuntimeError(f'{command} failed (exit {done.returncode}): '
                           f'{(done.stderr or done.stdout).strip().splitlines()[-1:]}')
    if words[0] == 'pytest':
        return _collection(done.stdout)
    return json.loads(done.stdout.strip().splitlines()[-1])


def measure(figures, root: Path) -> dict:
    """
    Measure ``figures`` in the tree at ``root``; return name -> the value as quoted.

    Each command runs once, however many of the figures it gives.
    """
    outputs = {}
    values = {}
    for figure in figures:
        if figure.command is None:
            measured = TREE_COUNTS[figure.key][1](root)
        else:
            if figure.command not in outputs:
                outputs[figure.command] = _run(figure.command, root)
            measured = outputs[figure.command][figure.key]
        values[figure.name] = figure.quoted(measured)
    return values


_HEADER = """\
# Measured figures

<!-- Written by make results; do not edit. -->

The figures README.md and doc/ quote, each as the command beside it measured it on the
date beside it. `make results` runs every command from the repository's root and writes
this file (`python -m nfmr_dlsmc.analysis.results_file doc/results.md`; a few minutes on
one core, most of them the runs on the chassis); `make results FIGURES='NAME ...'`
measures only the figures named and keeps the others. A page quotes a figure as its value
here, its unit after it or not, followed by `<!-- results:NAME -->` (names in lower case),
which a rendered page does not show. `test/test_results_file.py` fails when a quote
differs from this file, or a count of the tree (`design_records`, `robot_options`,
`test_functions`) from its row here.

`test_functions` counts each test function once; pytest collects a parametrised function
once per parameter set, so `tests_collected` (what `make test` runs) and `tests_slow`
(what `make test-all` adds) sum to more than it. The test recounts the functions, not the
collection: after a change of parameter sets alone, run `make results
FIGURES='tests_collected tests_slow'`.

| figure | value | unit | what | measured by | date |
|---|---:|---|---|---|---|
"""


def render(rows) -> str:
    """Return the results file of ``rows``."""
    return _HEADER + ''.join(
        f'| `{r.name}` | {r.value} | {r.unit} | {r.what} | {r.how} | {r.date} |\n' for r in rows)


def parse(text: str) -> dict:
    """Return the rows of a results file by name."""
    rows = {}
    for line in text.splitlines():
        cells = [cell.strip() for cell in line.strip().strip('|').split(' | ')]
        if len(cells) == 6 and cells[0].startswith('`'):
            row = Row(cells[0].strip('`'), *cells[1:])
            rows[row.name] = row
    return rows


def quotes(text: str) -> list:
    """
    Return each marker of a page as (line, name, number, unit) of its quote.

    A quote is a number, then its unit or not, then ``<!-- results:NAME -->``; a marker
    with no number before it, or inside a code block (where a page shows it), has None for
    the number; a quote without a unit None for the unit.
    """
    found = []
    fenced = False
    for line_no, line in enumerate(text.splitlines(), 1):
        if line.lstrip().startswith('```'):
            fenced = not fenced
        quoted = {m.start('name'): m.group('number', 'unit') for m in QUOTE.finditer(line)}
        found += [(line_no, m.group('name'),
                   *((None, None) if fenced else quoted.get(m.start('name'), (None, None))))
                  for m in MARKER.finditer(line)]
    return found


def main(argv=None) -> int:
    """Measure the figures and write the results file named in ``argv``; return the status."""
    args = sys.argv[1:] if argv is None else argv
    usage = 'usage: python -m nfmr_dlsmc.analysis.results_file OUT.md [NAME ...]'
    if args and args[0] in ('-h', '--help'):
        print(f'{usage}\n\nMeasure the figures NAME (all without one) and write OUT.md; '
              f"the names: {', '.join(f.name for f in FIGURES)}")
        return 0
    if not args or args[0].startswith('-'):
        print(usage, file=sys.stderr)
        return 2
    out, names = Path(args[0]), set(args[1:])
    unknown = names - {figure.name for figure in FIGURES}
    if unknown:
        print(f'no such figure: {", ".join(sorted(unknown))}', file=sys.stderr)
        return 2
    kept = parse(out.read_text()) if names and out.exists() else {}
    missing = [f.name for f in FIGURES if names and f.name not in names and f.name not in kept]
    if missing:
        print(f'{out} lacks {", ".join(missing)}: measure them too', file=sys.stderr)
        return 2
    todo = [figure for figure in FIGURES if not names or figure.name in names]
    values = measure(todo, Path.cwd())
    today = datetime.date.today().isoformat()
    out.write_text(render(row_of(f, values[f.name], today) if f.name in values
                          else kept[f.name] for f in FIGURES))
    return 0


if __name__ == '__main__':
    sys.exit(main())
