"""Plots of optimisation logs (matplotlib, written as PNG)."""

# what each phase's loss is, for the legend (phases are the ``desc`` of :func:`mi_voldis.optim.loop.optimize`)
PHASE_LOSS = {"bg refit": "background: L2 outside the masks", "full + bg": "full + background (joint)"}
# a fit logs held-out PSNR on its first `eval_views` test views while it runs, and its metrics.json scores
# every test view at the end: the legend says so, as the two numbers differ
HELD_OUT_LABEL = "held-out (first eval_views test views; metrics.json: all test views)"


def plot_log(path, log, title):
    """Training loss against wall-clock seconds, one line per phase (each phase optimises its own loss;
    a dotted line marks where one ends), and, when the log has any, PSNR against seconds beside it."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    psnr_keys = (("psnr", "train batch (full)"), ("psnr_bg", "train batch (bg)"), ("test_psnr", HELD_OUT_LABEL))
    has_psnr = any(key in r for r in log for key, _ in psnr_keys)
    fig, axes = plt.subplots(1, 2 if has_psnr else 1, figsize=(10 if has_psnr else 5.5, 3.6), squeeze=False)
    ax = axes[0]
    phases = []
    for r in log:
        name = r.get("phase", "")
        if not phases or phases[-1][0] != name:
            phases.append((name, []))
        phases[-1][1].append(r)
    for k, (name, rows) in enumerate(phases):
        label = PHASE_LOSS.get(name, f"{name}: L2 on all pixels" if name.startswith("full") else name or "loss")
        ax[0].semilogy([r["time"] for r in rows], [r["loss"] for r in rows], lw=0.8, label=label)
        if k:
            for a in ax:
                a.axvline(rows[0]["time"], color="grey", ls=":", lw=0.8)
    ax[0].set_xlabel("seconds")
    ax[0].set_ylabel("training loss")
    if len(phases) > 1 or phases and phases[0][0]:
        ax[0].legend(fontsize=7)
    if has_psnr:
        for key, label in psnr_keys:
            pts = [(r["time"], r[key]) for r in log if key in r]
            if pts:
                ax[1].plot(*zip(*pts), "o-" if key == "test_psnr" else "-", lw=0.8, ms=3, label=label)
        ax[1].set_xlabel("seconds")
        ax[1].set_ylabel("PSNR (dB)")
        ax[1].legend(fontsize=7)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
