"""The removal family: random scenes to choose defaults on and random scenes to judge them by.

Scene ``k`` of the family (``family00`` ... ``family23``) is the random scene of seed ``FIRST_SEED + k``
drawn with the rig kind ``KINDS[k % 4]`` (:func:`~mi_voldis.synth.random_scene.random_scene`: orbit,
forward grid, hand-held arc, hand-held forward rig), so forward-facing rigs come as often as orbits in
either half. The split is fixed here, before any result: the first ten scenes tune (defaults are chosen
on them alone), the rest check (``reports/removal.md`` leads with their worst scene). The seeds
start far from the ones the earlier random scenes (``random0`` ... ``random4``) were chosen on. Scenes
20 to 23 joined the check half after a candidate chosen on the tuning half failed the first ten
(reports/notes.md), to judge the next one on scenes no choice had looked at.
"""
FIRST_SEED = 1000
SIZE = 24
KINDS = ("orbit", "forward", "arc", "handheld")
TUNING = tuple(range(10))  # the scenes defaults may be chosen on
CHECK = tuple(range(10, SIZE))  # the scenes that judge them


def name(k):
    return f"family{k:02d}"


def index(scene):
    """The family index of a scene name ('family07' -> 7), or None for any other name."""
    if scene.startswith("family") and scene[len("family"):].isdigit():
        k = int(scene[len("family"):])
        if 0 <= k < SIZE:
            return k
    return None


def scene(k):
    """(seed, rig kind) of family scene ``k``."""
    if not 0 <= k < SIZE:
        raise ValueError(f"the removal family has scenes 0 to {SIZE - 1}, not {k}")
    return FIRST_SEED + k, KINDS[k % len(KINDS)]


def half(k):
    """'tuning' or 'check'."""
    return "tuning" if k in TUNING else "check"
