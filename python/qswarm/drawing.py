"""matplotlib for the figure modules: imported on the Agg backend, and figures saved so that the
same data gives the same bytes."""

import logging
import sys

DPI = 110


def import_matplotlib(prog):
    """(numpy, pyplot on the Agg backend), or None after telling the user what to install."""
    logging.getLogger("matplotlib").setLevel(logging.ERROR)  # no config/font-cache chatter
    try:
        import numpy as np
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as e:
        print(f"{prog}: needs numpy and matplotlib for {sys.executable} ({e}); on Debian: "
              "apt-get install python3-matplotlib python3-numpy", file=sys.stderr)
        return None
    return np, plt


def save_figure(plt, fig, path):
    """Writes and closes a figure; no software tag or date: the same data gives the same bytes."""
    fig.savefig(path, dpi=DPI, metadata={"Software": None})
    plt.close(fig)
