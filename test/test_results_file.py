"""
The figures the docs quote are doc/results.md's, and its counts of the tree are current.

``make results`` measures the figures of :mod:`nfmr_dlsmc.analysis.results_file` and writes
doc/results.md; README.md and doc/*.md quote a figure as its value followed by
``<!-- results:NAME -->``. The fast tests run no simulation: they hold each quote to the
file, the file's rows to the module's figures (a figure measured otherwise is measured
again), and the counts that are cheap to make again (design records, robot options, test
functions) to the tree. The slow test measures the kinematic figures again.
"""

import datetime
from pathlib import Path

from nfmr_dlsmc.analysis.results_file import (
    count_test_functions,
    DESIGN_RECORD,
    Figure,
    FIGURES,
    main,
    measure,
    parse,
    quotes,
    render,
    row_of,
    TREE_COUNTS,
)
import pytest

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / 'doc' / 'results.md'
#: The pages that quote figures: the front page and doc/, the results file aside.
PAGES = [ROOT / 'README.md'] + sorted(p for p in (ROOT / 'doc').glob('*.md') if p != RESULTS)


def _rows() -> dict:
    return parse(RESULTS.read_text())


def _quotes() -> list:
    """Return (page:line, name, number, unit) of every quote of every page."""
    return [(f'{page.relative_to(ROOT)}:{line}', name, number, unit)
            for page in PAGES for line, name, number, unit in quotes(page.read_text())]


@pytest.mark.sources
def test_every_quote_in_the_docs_is_the_results_file_s():
    rows = _rows()
    wrong = []
    for where, name, number, unit in _quotes():
        row = rows.get(name)
        if row is None:
            wrong.append(f'{where}: {name} is no figure of doc/results.md')
        elif number is None:
            wrong.append(f'{where}: {name} has no number right before it (or is in a code block)')
        elif number != row.value:
            wrong.append(f'{where}: {name} quoted as {number}, doc/results.md has {row.value}')
        elif unit is not None and unit != row.unit:
            wrong.append(f'{where}: {name} quoted in {unit}, doc/results.md has {row.unit!r}')
    assert not wrong, '\n'.join(wrong)


@pytest.mark.sources
def test_every_figure_is_quoted_somewhere():
    quoted = {name for _, name, _, _ in _quotes()}
    assert [f.name for f in FIGURES if f.name not in quoted] == [], (
        'a figure no page quotes: quote it or take it out of results_file.FIGURES')


@pytest.mark.sources
def test_the_results_file_holds_each_figure_as_the_module_measures_it():
    rows = _rows()
    assert list(rows) == [f.name for f in FIGURES], 'doc/results.md is out of date: make results'
    otherwise = [name for name, figure in zip(rows, FIGURES)
                 if rows[name][2:5] != (figure.unit, figure.what, figure.how)]
    assert not otherwise, (f'measured otherwise than doc/results.md says: make results '
                           f"FIGURES='{' '.join(otherwise)}'")


@pytest.mark.sources
@pytest.mark.parametrize('key', TREE_COUNTS)
def test_the_counts_of_the_tree_are_the_results_file_s(key):
    figure = next(f for f in FIGURES if f.command is None and f.key == key)
    assert _rows()[figure.name].value == measure([figure], ROOT)[figure.name], (
        f'doc/results.md is out of date: make results FIGURES={figure.name}')


@pytest.mark.sources
def test_the_design_records_are_numbered_from_one_to_their_count():
    numbers = [int(n) for n in DESIGN_RECORD.findall((ROOT / 'doc' / 'design.md').read_text())]
    assert numbers == list(range(1, len(numbers) + 1))


def test_a_quote_is_a_number_its_unit_or_not_then_the_marker():
    text = ('IAE 13.3473 <!-- results:table2_iae --> (−1.7 % <!-- results:a -->, +2.1 %'
            '<!-- results:b -->), D1–D31 <!-- results:design_records -->, 0.754 mm\n'
            'held <!-- results:c -->, 7 <!-- results:d_1 -->: `<!-- results:NAME -->`\n'
            '```\n0.5 <!-- results:e -->\n```\n')
    assert quotes(text) == [(1, 'table2_iae', '13.3473', None), (1, 'a', '1.7', '%'),
                            (1, 'b', '+2.1', '%'), (1, 'design_records', '31', None),
                            (2, 'c', None, None), (2, 'd_1', '7', None),
                            (4, 'e', None, None)]


def test_a_figure_is_quoted_in_its_unit_with_its_digits():
    def figure(**kwargs):
        return Figure('x', 'what', 'nfmr-eval --json', 'key', **kwargs)

    assert figure(unit='mm', scale=1e3, spec='#.3g').quoted(7.543e-4) == '0.754'
    assert figure(unit='mm', scale=1e3, spec='#.3g').quoted(1.0e-4) == '0.100'
    assert figure(unit='%', spec='+.1f', relative_to=13.5757).quoted(13.3473) == '-1.7'
    assert figure(unit='%', scale=100.0, spec='.0f').quoted(0.0) == '0'
    assert figure(spec='.4f').quoted(7.009) == '7.0090'
    assert figure(spec='.4f').quoted(None) == '—'
    assert figure().quoted(31) == '31'


def test_the_results_file_reads_back_as_written():
    rows = [row_of(figure, str(k), '2026-01-02') for k, figure in enumerate(FIGURES)]
    assert list(parse(render(rows)).values()) == rows


def test_test_functions_are_counted_once_each_parametrised_or_in_a_class(tmp_path):
    (tmp_path / 'test').mkdir()
    (tmp_path / 'test' / 'test_a.py').write_text(
        'import pytest\n\n\ndef helper():\n    pass\n\n\n'
        "@pytest.mark.parametrize('n', [1, 2, 3])\ndef test_one(n):\n    pass\n\n\n"
        'class TestTwo:\n    def test_two(self):\n        pass\n\n    def other(self):\n'
        '        pass\n\n\nclass Helper:\n    def test_not(self):\n        pass\n')
    (tmp_path / 'test' / 'helpers.py').write_text('def test_not():\n    pass\n')
    assert count_test_functions(tmp_path) == 2


def test_named_figures_are_measured_again_and_the_others_kept(tmp_path, monkeypatch):
    monkeypatch.chdir(ROOT)
    out = tmp_path / 'results.md'
    out.write_text(RESULTS.read_text())
    kept = parse(out.read_text())
    assert main([str(out), 'design_records']) == 0
    rows = parse(out.read_text())
    assert rows['design_records'].date == datetime.date.today().isoformat()
    assert {n: r for n, r in rows.items() if n != 'design_records'} == {
        n: r for n, r in kept.items() if n != 'design_records'}


def test_an_unknown_figure_or_one_the_file_lacks_is_refused(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(ROOT)
    out = tmp_path / 'results.md'
    out.write_text(render([]))
    assert main([str(out), 'no_such_figure']) == 2
    assert 'no such figure: no_such_figure' in capsys.readouterr().err
    assert main([str(out), 'design_records']) == 2
    assert 'lacks table2_iae' in capsys.readouterr().err
    assert out.read_text() == render([])


def test_help_measures_nothing_and_an_option_is_no_file_name(tmp_path, monkeypatch, capsys):
    # `--help` once measured every figure and wrote them to a file named '--help'.
    monkeypatch.chdir(tmp_path)
    assert main(['--help']) == 0
    assert 'usage:' in capsys.readouterr().out
    assert main(['--out', 'x.md']) == 2
    assert 'usage:' in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
@pytest.mark.commands
def test_the_kinematic_figures_measure_as_the_results_file_says():
    kinematic = [f for f in FIGURES if f.command is not None
                 and f.command.startswith('nfmr-eval') and '--plant pybullet' not in f.command]
    rows = _rows()
    assert measure(kinematic, ROOT) == {f.name: rows[f.name].value for f in kinematic}
