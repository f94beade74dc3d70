"""The Python API the README shows: its example runs as printed, its names are exported."""

import contextlib
import importlib
import io
from pathlib import Path
import re

import nfmr_dlsmc
import pytest

README = Path(__file__).resolve().parents[1] / 'README.md'
CORE = sorted(p.stem for p in (Path(nfmr_dlsmc.__file__).parent / 'core').glob('[!_]*.py'))


def _python_blocks():
    return re.findall(r'```python\n(.*?)```', README.read_text(), re.S)


def test_the_readme_python_example_prints_the_case1_iae():
    (example,) = _python_blocks()
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(example, 'README.md', 'exec'), {})
    # The paper's Case 1 on the kinematic model: IAE 13.3473 m s (Table 2: 13.5757).
    assert float(out.getvalue()) == pytest.approx(13.3473, abs=5e-5)


def test_the_readme_example_imports_only_the_package_api():
    (example,) = _python_blocks()
    imported = re.findall(r'^from (\S+) import (.+)$', example, re.M)
    assert imported and all(module == 'nfmr_dlsmc' for module, _ in imported)
    for _, names in imported:
        for name in names.split(','):
            assert name.strip() in nfmr_dlsmc.__all__


def test_every_exported_name_exists():
    assert len(set(nfmr_dlsmc.__all__)) == len(nfmr_dlsmc.__all__)
    for name in nfmr_dlsmc.__all__:
        assert getattr(nfmr_dlsmc, name) is not None


@pytest.mark.parametrize('name', CORE)
def test_every_core_module_declares_its_api(name):
    module = importlib.import_module(f'nfmr_dlsmc.core.{name}')
    assert module.__all__, f'nfmr_dlsmc.core.{name} has an empty __all__'
    for exported in module.__all__:
        assert hasattr(module, exported), f'{name}.__all__ names missing {exported}'
        assert not exported.startswith('_')
