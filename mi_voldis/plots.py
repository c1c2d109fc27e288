"""Plots of optimisation logs (matplotlib, written as PNG)."""


def plot_log(path, log, title):
    """Training loss and PSNR against wall-clock seconds."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    t = [r["time"] for r in log]
    fig, ax = plt.subplots(1, 2, figsize=(10, 3.6))
    ax[0].semilogy(t, [r["loss"] for r in log], lw=0.8)
    ax[0].set_xlabel("seconds")
    ax[0].set_ylabel("training loss")
    for key, label in (("psnr", "train batch (full)"), ("psnr_bg", "train batch (bg)"), ("test_psnr", "held-out")):
        pts = [(r["time"], r[key]) for r in log if key in r]
        if pts:
            ax[1].plot(*zip(*pts), "o-" if key == "test_psnr" else "-", lw=0.8, ms=3, label=label)
    ax[1].set_xlabel("seconds")
    ax[1].set_ylabel("PSNR (dB)")
    if ax[1].get_legend_handles_labels()[0]:
        ax[1].legend()
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
