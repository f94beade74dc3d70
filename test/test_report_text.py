"""
The comparison report states what it computes, not what a run once measured (issue 39).

A sentence such as "the paper reports about +-0.18 rad" or "a 1000 kg body" written into
the report's code goes stale with the next change; measured prose lives in
doc/comparison.md, dated, with the command that measured it. So the literal text of
``nfmr_dlsmc/analysis/comparison_report.py`` holds no number with a unit: every such figure
it prints is formatted from the results or from a named constant (the input limits, the
tolerances, the scenarios, the chassis). The rule reads the literal text only (string
constants and the literal parts of f-strings; docstrings and comments aside), so a figure
from a placeholder, ``f'{omega_max:g} rad/s'``, passes. A measured claim without a number
("the laws with a boundary layer stay smooth") is beyond it.
"""

import ast
from pathlib import Path
import re

import pytest

pytestmark = pytest.mark.sources

ROOT = Path(__file__).resolve().parents[1]
#: The modules held to the rule.
REPORTS = ('nfmr_dlsmc/analysis/comparison_report.py',)
#: A number, then a unit of the report's figures (longer units first).
FIGURE = re.compile(
    r'(?<![\w.])[0-9]+(?:\.[0-9]+)?(?:e-?[0-9]+)?\s?'
    r'(?:mm|cm|µm|um|ms|µs|us|rad/s²|rad/s\^2|rad/s|mrad|rad|m/s|m|s|kHz|Hz|kg|Nm|N|deg|%)'
    r'(?![\w/^²])')


def literal_figures(source: str) -> list[tuple[int, str]]:
    """Return (line, figure) of each number with a unit in the literal text of ``source``."""
    tree = ast.parse(source)
    docstrings = {id(node.body[0].value) for node in ast.walk(tree)
                  if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef,
                                       ast.AsyncFunctionDef))
                  and node.body and isinstance(node.body[0], ast.Expr)}
    return [(node.lineno, match.group(0)) for node in ast.walk(tree)
            if isinstance(node, ast.Constant) and isinstance(node.value, str)
            and id(node) not in docstrings
            for match in FIGURE.finditer(node.value)]


def test_the_rule_finds_a_written_figure_and_passes_a_formatted_one():
    written = literal_figures(
        'def f(bands):\n'
        '    """Return the 1 mm figure (a docstring is not report text)."""\n'
        "    return (f'{bands:g} rad' + ' holds, the paper reports about +-0.18 rad'\n"
        "            f' and a 1000 kg body at {bands:.1f}% of 1.59 rad/s, 12.5% of 2 ms')\n")
    assert [figure for _, figure in written] == ['0.18 rad', '1000 kg', '1.59 rad/s',
                                                 '12.5%', '2 ms']
    assert literal_figures("x = f'{a:g} mm, {b:.2f} rad/s², Table 2, x0 = (1, 4, 0), pi/6'") == []


@pytest.mark.parametrize('path', REPORTS)
def test_the_report_writes_no_figure_of_its_own(path):
    found = literal_figures((ROOT / path).read_text())
    assert not found, (f'{path}: figures written into the report text (format them from the '
                       f'results or a named constant; measured prose goes to doc/): {found}')
