"""PNG figures without a display: matplotlib's pyplot on the Agg backend, and what every plot of
the reports shares."""
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (the front ends draw with figures.plt)


def no_values_note(ax, norm):
    """Say on empty axes that `norm` has no value a log scale can show."""
    ax.text(0.5, 0.5, f"no finite positive values of {norm}", ha="center", va="center",
            transform=ax.transAxes)


def save_png(fig, path, dpi):
    """Lay out, save and close a figure."""
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
