"""The scenes of a bench report's family.json named on the command line, or one line saying why not (shared by
``ceiling.py`` and ``iou_views.py``)."""
import json
import os
import sys


def scenes_from_argv(doc, script):
    """``{scene: entry}`` of the family report ``sys.argv[1]``; exits with ``doc``'s usage line when the
    arguments are wrong, or with one line naming the file when it is not a family report."""
    if len(sys.argv) != 2:
        raise SystemExit(doc.strip().splitlines()[-1].strip())
    try:
        with open(sys.argv[1]) as f:
            return json.load(f)["scenes"]
    except (OSError, ValueError, KeyError) as e:
        raise SystemExit(f"{os.path.basename(script)}: {sys.argv[1]}: not a family report ({type(e).__name__}: {e})")
