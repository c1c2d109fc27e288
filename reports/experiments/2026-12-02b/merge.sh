#!/bin/sh
# one work folder for family/report.py: each scene's fit and dataset as the last report linked them
# (OLD: the thirty-first session's merged folder), its default row from this session's package refits
# (PKG/{A,B,chkA,chkB}/removal); symbolic links only.
#   sh merge.sh OLD PKG MERGED
set -e
OLD=$1; PKG=$2; M=$3
[ -e "$M" ] && { echo "merge.sh: $M exists; give a new folder"; exit 1; }
mkdir -p "$M/runs" "$M/data" "$M/removal"
for s in $(seq -w 0 23); do
  cp -P "$OLD/runs/family${s}_0" "$M/runs/"
  cp -P "$OLD/data/family$s" "$M/data/"
  row=$(ls -d "$PKG"/*/removal/family$s 2>/dev/null | head -1)
  [ -n "$row" ] || { echo "merge.sh: no refit of family$s under $PKG"; exit 1; }
  ln -s "$row" "$M/removal/family$s"
done
echo "$M: 24 scenes"
