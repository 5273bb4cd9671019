"""build_engine.sh: the TensorRT recipe run on the board (``trtexec`` ships with JetPack).

Shapes: batch 1..64 (the paper times at batch 1 and warms up in batches of 64), optimised for
batch 1; time fixed for unrolled SNNs, 1..4T (optimised for T) for whole-sequence LSTMs.
"""

from __future__ import annotations

TENSORRT_FOR_JETPACK = {13: "8.2 (JetPack 4.6.x)", 17: "8.5 / 8.6 (JetPack 5.x / 6.0)", 20: "10.3+ (JetPack 6.1+)"}
MAX_BATCH = 64


def _shape(dims: list) -> str:
    return "x".join(str(d) for d in dims)


def shape_flags(inputs: list[dict], steps: int) -> tuple[str, str, str]:
    """trtexec --minShapes/--optShapes/--maxShapes values for a model's inputs."""
    lo, opt, hi = [], [], []
    for spec in inputs:
        dims_lo, dims_opt, dims_hi = [], [], []
        for d in spec["shape"]:
            if d == "batch":
                dims_lo.append(1), dims_opt.append(1), dims_hi.append(MAX_BATCH)
            elif d == "time":
                dims_lo.append(1), dims_opt.append(steps), dims_hi.append(4 * steps)
            else:
                dims_lo.append(d), dims_opt.append(d), dims_hi.append(d)
        lo.append(f"{spec['name']}:{_shape(dims_lo)}")
        opt.append(f"{spec['name']}:{_shape(dims_opt)}")
        hi.append(f"{spec['name']}:{_shape(dims_hi)}")
    return ",".join(lo), ",".join(opt), ",".join(hi)


def build_engine_script(manifest: dict) -> str:
    """The shell script text (deterministic for a given manifest)."""
    steps = manifest["time_steps"]
    blocks = []
    for variant in manifest["variants"]:
        lo, opt, hi = shape_flags(variant["inputs"], steps)
        plan = variant["file"].replace(".onnx", ".plan")
        blocks.append(
            f'echo "building {plan} from {variant["file"]} ($PRECISION_LABEL)"\n'
            f'"$TRTEXEC" --onnx={variant["file"]} --saveEngine={plan} \\\n'
            f"    --minShapes={lo} \\\n    --optShapes={opt} \\\n    --maxShapes={hi} \\\n"
            f'    ${{PRECISION[@]+"${{PRECISION[@]}}"}} ${{EXTRA[@]+"${{EXTRA[@]}}"}}\n'
        )
    opset = manifest["opset"]
    return f"""#!/usr/bin/env bash
# Build TensorRT engines for this snncc Jetson artefact. Run it ON the Jetson (TensorRT engines are
# specific to the GPU and TensorRT version that built them).
#
#   ./build_engine.sh            float32 (what snncc validated against the IR reference)
#   ./build_engine.sh --fp16     half precision (snncc's fp16 emulation: see manifest.json "validation.fp16")
#   ./build_engine.sh --int8 --calib=CACHE
#                                int8 needs a calibration cache: without one trtexec uses dummy scales and
#                                the results are meaningless; spikes are threshold crossings, so int8
#                                membranes can change them (check with `snncc check` first). TensorRT 10
#                                deprecates implicit calibrators in favour of explicit Q/DQ nodes in the ONNX.
#
# Written for JetPack {manifest["jetpack"]} (ONNX opset {opset}, TensorRT {TENSORRT_FOR_JETPACK.get(opset, "?")}).
# Recurrent graphs run on the GPU (DLA is for CNN layers). Set TRTEXEC to override the trtexec path.
set -euo pipefail
cd "$(dirname "$0")"
TRTEXEC="${{TRTEXEC:-$(command -v trtexec || echo /usr/src/tensorrt/bin/trtexec)}}"
PRECISION=()
PRECISION_LABEL="fp32"
EXTRA=()
INT8=0
CALIB=""
for arg in "$@"; do
  case "$arg" in
    --fp16) PRECISION+=(--fp16); PRECISION_LABEL="fp16" ;;
    --int8) INT8=1 ;;
    --calib=*) CALIB="${{arg#--calib=}}" ;;
    *) EXTRA+=("$arg") ;;
  esac
done
if [ "$INT8" = 1 ]; then
  if [ -z "$CALIB" ]; then
    echo "build_engine.sh: --int8 needs --calib=CACHE (a calibration cache); refusing to build with dummy scales" >&2
    exit 2
  fi
  PRECISION+=(--int8 "--calib=$CALIB"); PRECISION_LABEL="int8+${{PRECISION_LABEL}}"
fi
if [ ! -x "$TRTEXEC" ] && ! command -v "$TRTEXEC" >/dev/null 2>&1; then
  echo "build_engine.sh: trtexec not found (set TRTEXEC=/path/to/trtexec)" >&2
  exit 2
fi
{"".join(blocks)}echo "done: run.py uses the .plan files when TensorRT is importable"
"""
