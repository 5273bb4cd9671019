"""Place a LoihiNetwork's neurons on cores under every per-core limit at once, using few cores.

Model of a map: every non-input layer is cut into contiguous slices; a core holds at most one
slice per layer (slices of several layers may share a core); every core stays within each limit
of ``ChipSpec.limits()`` as counted in ``usage.py``.

Method (one module per step):
  1. fan-in wider than a core's input axons -> relay layer (``fanin.py``; changes the network, recorded).
  2. the network as projections and profile keys (``projections.py``).
  3. each layer alone, destinations first: the fewest contiguous slices that each fit a core (``slicing.py``).
  4. first-fit-decreasing packing of the slices onto cores (``packing.py``).
  5. small all-dense networks: exact search over neurons per layer per core; the lower bound; a
     core over its output axons gets a layer cut finer and the slices repacked (``search.py``).
  6. core ids in network order; chip = id // cores per chip. Every core is checked against every
     design rule before the map is returned.
"""

from __future__ import annotations

from snncc.targets.kit import InternalError, SnnccError
from snncc.targets.loihi.mapping.coremap import CoreMap, CoreRecord, CoreUsage, LayerSlice
from snncc.targets.loihi.mapping.fanin import split_wide_fan_in
from snncc.targets.loihi.network import LoihiNetwork
from snncc.targets.loihi.mapping.projections import NetworkModel
from snncc.targets.loihi.mapping.resources import LOIHI1, ChipSpec, check_core, check_core_count
from snncc.targets.loihi.mapping.search import dp_min_cores, lower_bound, pack_and_repair
from snncc.targets.loihi.mapping.slicing import dense_layer_minimum, slice_layers

METHOD = ("per-layer fewest slices (dense: ceil(n / m_max); sparse: greedy maximal or equal) + "
          "first-fit-decreasing packing{dp} + output-axon repair")


def map_network(network: LoihiNetwork, chip: ChipSpec = LOIHI1) -> CoreMap:
    """Place every non-input layer on cores under all of ``chip``'s limits; deterministic.

    Returns a ``CoreMap`` whose ``network`` is the network actually mapped (with fan-in relays when
    a layer's fan-in exceeds a core's input axons; see ``transforms``). Raises ``SnnccError`` naming
    the limit and the layer when no map can exist.
    """
    mapped, transforms = split_wide_fan_in(network, chip)
    model = NetworkModel(mapped, chip)
    layer_minimum = dense_layer_minimum(model)
    bounds, why = slice_layers(model)
    dp = dp_min_cores(model)
    lb, lb_method = lower_bound(model, layer_minimum, dp[0] if dp else None)
    cores, usage, forced, why = pack_and_repair(model, bounds, why, dp)
    bad = check_core_count(len(cores), chip)
    if bad:
        raise SnnccError(bad[0].message() + "; no map exists", field="network")
    records = [CoreRecord(core=c, chip=c // chip.cores_per_chip,
                          layers=[LayerSlice(model.layers[i].name, i, a, z) for i, a, z in slices],
                          usage=CoreUsage.from_mapping({k: v[c] for k, v in usage.items()}))
               for c, slices in enumerate(cores)]
    for rec in records:           # the map is checked against every design rule before it is returned
        v = check_core({**rec.usage.as_dict(), "core": rec.core, "layers": [{"layer": s.layer} for s in rec.layers]},
                       chip)
        if v:
            raise InternalError(v[0].message() + " (the partitioner produced an invalid map)", field="core map")
    if lb > len(records):
        raise InternalError(f"lower bound {lb} above the map's {len(records)} cores", field="core map")
    idx = range(1, len(model.layers))
    return CoreMap(
        chip=chip, cores=records, lower_bound=lb, lower_bound_method=lb_method,
        method=METHOD.format(dp=" + exact count search" if dp else ""),
        layer_limits={model.layers[i].name: f"{len(forced[i]) - 1} slice(s); {why[i]}" for i in idx},
        transforms=transforms,
        network_layers=[{"index": j, "name": lay.name, "kind": lay.kind, "n": lay.n} for j, lay in enumerate(model.layers)],
        network=mapped)


def core_lower_bound(network: LoihiNetwork, chip: ChipSpec = LOIHI1) -> int | None:
    """The fewest cores any map of ``network`` can use (``search.lower_bound`` without the exact search): what a
    scale rule would cost, without mapping it. None when the network needs fan-in relays (mapping decides)."""
    mapped, transforms = split_wide_fan_in(network, chip)
    if transforms:
        return None
    model = NetworkModel(mapped, chip)
    return int(lower_bound(model, dense_layer_minimum(model), None)[0])


def map_bundle(source, options) -> CoreMap:
    """The ``map`` capability: the core map of the written bundle at ``source`` (``snncc map MODEL`` compiles
    the model first, with compile's options, then maps the written bundle). ``options`` (``LoihiOptions``): a
    timing, weight scale or replicas other than the bundle was compiled with is refused in one line (compile
    fixed them)."""
    from pathlib import Path

    from snncc.targets.loihi.bundle.read import read_bundle

    source = Path(source)
    network = read_bundle(source)
    recorded = network.metadata.get("compile_options")
    recorded = recorded if isinstance(recorded, dict) else {}
    for key in ("timing", "scale", "replicas"):
        value = getattr(options, key)
        if value is not None and value != recorded.get(key):
            raise SnnccError("does not apply to a Loihi bundle (its timing, weight scale and replicas are fixed); "
                             "compile the model with it, then map the bundle", file=str(source),
                             field="--" + key.replace("_", "-"))
    try:
        return map_network(network)
    except SnnccError as err:
        raise err.with_file(str(source)) from None
