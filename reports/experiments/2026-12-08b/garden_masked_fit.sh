#!/bin/bash
# #46 item 3 on garden: the box masks given to the full field's fit (so free_space marks the space in front of the
# vase) against today's flow (the full field fitted without masks, the masks made from the box after it, the
# background refitted with them). W: a folder for the runs; the capture is read from ../shared/data/garden.
#   bash garden_masked_fit.sh W          (from the repository root; W/garden_A: the default fit without masks)
set -e
W=$1; G=${GARDEN:-../shared/data/garden}
PY=${PY:-python}
[ -f $W/garden_A/checkpoints/last.npz ] || $PY scripts/train.py $G --out $W/garden_A --keep-checkpoints --quiet
[ -d $W/masks ] || $PY scripts/make_masks.py $G --out $W/masks --run $W/garden_A --box 0.45,-0.1,-1.05,1.77,0.7,-0.15
[ -d $W/data ] || $PY -c "from mi_voldis.bench.masks import masked_copy; masked_copy('$G', '$W/masks', '$W/data')"
# today's flow: the background refitted from the maskless full field with the box masks
$PY -m mi_voldis.bench.strategies $W/garden_A guided $W/score_A $W/data > $W/score_A.log 2>&1 &
# the masks given to the fit: the full field with free_space, then its own background, scored as it is
[ -f $W/garden_B/checkpoints/last.npz ] || $PY scripts/train.py $W/data --out $W/garden_B --keep-checkpoints --quiet
$PY -m mi_voldis.bench.strategies $W/garden_B guided $W/score_B > $W/score_B.log 2>&1
wait
