#!/usr/bin/env bash
# TALOS's mass and CoM height above its soles at the half-sitting posture of its SRDF, with stride's own
# model code (`stride model eval`): the denominator of the stiffness scaling of docs/flexible-joints.md
# (Romualdi 2022, Table 9.1 was measured on TALOS).
#
#     bash tools/reference/talos_com_height.sh [STRIDE_BINARY]     (default: target/release/stride)
#
# Uses example-robot-data (tools/reference/example-robot-data-dir.sh, nothing committed).
set -euo pipefail
stride="${1:-target/release/stride}"
robots=$(bash "$(dirname "$0")/example-robot-data-dir.sh")
talos="$robots/talos_data"
state=$(mktemp --suffix=.json)
trap 'rm -f "$state"' EXIT
python3 - "$talos/srdf/talos.srdf" "$state" <<'PY'
import json, re, sys
srdf = open(sys.argv[1]).read()
block = srdf[srdf.index('name="half_sitting"'):]
block = block[: block.index("</group_state>")]
values = dict(re.findall(r'name="([a-z_0-9]+)" value="([^"]+)"', block))
root = [float(x) for x in values.pop("root_joint").split()]
json.dump({"base_position": root[:3], "base_orientation_xyzw": root[3:],
           "joint_positions": {k: float(v) for k, v in values.items()},
           "frames": ["left_sole_link", "right_sole_link"]}, open(sys.argv[2], "w"))
PY
"$stride" model eval "$talos/robots/talos_full_v2.urdf" --state "$state" 2>/dev/null | python3 -c '
import json, sys
d = json.load(sys.stdin)
sole_z = d["frames"]["left_sole_link"]["position"][2]
print("TALOS half-sitting: mass %.2f kg, CoM %.4f m above the soles" % (d["total_mass"], d["com_position"][2] - sole_z))
'
