"""
The heat maps of ``nfmr-compare --matrix`` (``matrix.png``): a law's hold in every cell.

matplotlib is imported where the figure is drawn: the matrix's runs and tables need it not.
"""

from pathlib import Path

from nfmr_dlsmc.analysis.comparison_matrix import cell_text, MARKS, SCENARIO_TITLES
from nfmr_dlsmc.baselines.registry import controller_label
import numpy as np


def write_matrix_figure(path: Path, document: dict) -> Path:
    """
    Draw a heat map per law of the hold distance p99 of a ``matrix.json`` document.

    A panel per law, a row per cell (steering, sensing) and a column per reference; one
    logarithmic colour scale for every panel, grey where a run has no figure; each cell
    gives the distance in mm with the signs of the marks it earns
    (:data:`~nfmr_dlsmc.analysis.comparison_matrix.MARKS`). Returns ``path``.
    """
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm

    laws, cells = document['laws'], document['cells']
    references = list(document['runs'])
    values = np.full((len(laws), len(cells), len(references)), np.nan)
    for k, name in enumerate(laws):
        for i, cell in enumerate(cells):
            for j, reference in enumerate(references):
                figures = document['runs'][reference].get(cell, {}).get(name) or {}
                if figures.get('hold_distance_p99') is not None:
                    values[k, i, j] = 1000.0 * figures['hold_distance_p99']
    finite = values[np.isfinite(values) & (values > 0.0)]
    norm = LogNorm(float(finite.min()), float(max(finite.max(), finite.min() * 10.0))) \
        if finite.size else LogNorm(0.1, 100.0)
    cmap = matplotlib.colormaps['RdYlGn_r'].with_extremes(bad='0.85')  # grey: no figure
    fig, axes = plt.subplots(1, len(laws), figsize=(2.4 * len(laws) + 2.6, 5.2),
                             squeeze=False, constrained_layout=True)
    for k, (ax, name) in enumerate(zip(axes[0], laws)):
        image = ax.imshow(np.ma.masked_invalid(values[k]), cmap=cmap, norm=norm,
                          aspect='auto')
        for i, cell in enumerate(cells):
            rate_limit = cells[cell]['steer_rate_limit']
            for j, reference in enumerate(references):
                figures = document['runs'][reference].get(cell, {}).get(name)
                red, green, blue, _ = cmap(norm(values[k, i, j]))
                dark = 0.299 * red + 0.587 * green + 0.114 * blue < 0.45
                ax.text(j, i, cell_text(figures, rate_limit), ha='center', va='center',
                        fontsize=8, color='white' if dark else 'black')
        ax.set_xticks(range(len(references)),
                      [SCENARIO_TITLES.get(r, r).split(' from')[0] for r in references],
                      fontsize=8)
        ax.set_yticks(range(len(cells)),
                      [f"{c['steering']}, {c['sensing']}" for c in cells.values()]
                      if k == 0 else [], fontsize=8)
        ax.set_title(controller_label(name), fontsize=9)
    fig.colorbar(image, ax=axes[0].tolist(), label='hold distance p99 [mm]')
    fig.suptitle(f"Hold distance p99 [mm] from t = {document['hold_from']:g} s on\n"
                 + '    '.join(f'{sign} {short}' for sign, _, short in MARKS.values()),
                 fontsize=9)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
