import sys

import mi_voldis  # noqa
from mi_voldis.field_state import with_sh_degree
from mi_voldis.fit.state import FitState
from mi_voldis.optim.adam import Adam

path = sys.argv[1]
s = FitState.load(path, Adam({}, 0.9, 0.99))
print(s.phase, {k: (f.sh_degree, f.grey, f.sh_gate) for k, f in s.fields.items()})
s.fields = {"full": with_sh_degree(s.fields["full"], 0)}
s.save(path, s.phase, s.step)
print(FitState.load(path, Adam({}, 0.9, 0.99)).fields["full"].sh_degree)
