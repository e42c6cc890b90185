"""Generate scaled missions for the benchmarks.

Each family reuses the HDDL domain, goal model and configuration of a reference mission (read
from the reference corpus by path, never copied) and writes a world knowledge file of its own
with ``n`` entities, every one of which produces decomposition work:

* ``delivery``: food-logistics delivery, ``n`` deliveries, every patient able to fetch (so each
  delivery has three alternative decompositions: 3^n valid mission decompositions);
* ``pickup``: food-logistics pickup, ``n`` pickups, every patient able to open the door;
* ``vital-signs``: ``n`` occupied rooms with two patients each (comma-separated list), with
  varied conditions so that the three methods of CollectVitalSigns are all exercised;
* ``coupled``: the delivery family where every delivery's GetFood may also mark the shared
  kitchen busy or free (predicate ``busy``, attribute ``is_busy`` of Location; methods
  ``food-pickup-mark`` and ``food-pickup-free``): the deliveries interact through one fact, so
  their choices form one component instead of n independent ones.
* ``coupled-sequence``: the same domain, but the kitchen visits are ``n`` GetFood tasks in one
  ``;`` sequence (a goal model of its own: ``[G2;G3;...]``, each subgoal ``[AT1;AT2;...]``), and the methods test the shared
  fact that earlier visits leave behind: ``food-pickup`` needs the kitchen free,
  ``food-pickup-mark`` marks it busy and needs it free, ``food-pickup-free`` frees it.  The state
  flows from block to block (``busy`` is initially false), so the count satisfies
  ``free' = 2 free + busy``, ``busy' = free``: about 2.414^n valid mission decompositions.

    python benchmarks/generate.py FAMILY N OUT_DIR   -> prints the configuration path
"""
from __future__ import annotations

import json
import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
REFERENCE = Path(os.environ.get("MUTROSE_REFERENCE", ROOT.parent / "shared" / "reference"))
if not REFERENCE.is_absolute():
    REFERENCE = (ROOT / REFERENCE).resolve()

FAMILIES = {
    # family: (reference folder, configuration template, goal model)
    "delivery": ("scalability/food-logistics-delivery", "configurationDelivery1.json", "FoodLogisticsDelivery.txt"),
    "pickup": ("scalability/food-logistics-pickup", "configurationPickup1.json", "FoodLogisticsPickup.txt"),
    "vital-signs": ("missions/vital-signs-monitoring", "configuration.json", "VitalSignsMonitoring.txt"),
    "coupled": ("scalability/food-logistics-delivery", "configurationDelivery1.json", "FoodLogisticsDelivery.txt"),
    "coupled-sequence": ("scalability/food-logistics-delivery", "configurationDelivery1.json", ""),
}

# what the coupled family adds to the delivery domain (written next to the world, never into the
# reference corpus)
COUPLED_PREDICATE = "\t\t(busy ?l - location)\n"
COUPLED_DOMAIN = """
\t(:method food-pickup-mark
\t\t:parameters (?r - robot ?l - location)
\t\t:task (GetFood ?r ?l)
\t\t:ordered-subtasks (and (navto ?r ?l) (wait-for-food ?r ?l) (mark-busy ?r ?l))
\t)
\t(:method food-pickup-free
\t\t:parameters (?r - robot ?l - location)
\t\t:task (GetFood ?r ?l)
\t\t:ordered-subtasks (and (navto ?r ?l) (wait-for-food ?r ?l) (mark-free ?r ?l))
\t)
\t(:action mark-busy
\t\t:parameters (?r - robot ?l - location)
\t\t:effect (and (busy ?l))
\t)
\t(:action mark-free
\t\t:parameters (?r - robot ?l - location)
\t\t:effect (and (not (busy ?l)))
\t)
"""
COUPLED_MAPPING = {"type": "attribute", "name": "is_busy", "relates_to": "Location", "belongs_to": "world_db",
                   "mapped_type": "predicate", "map": {"pred": "busy", "arg_sorts": ["location"]}}


def food_world(n: int, request: str, location_field: str) -> str:
    """n requests (``Delivery`` or ``Pickup``), each for its own patient at its own location,
    every patient able to fetch and to open the door."""
    parts = ["<world_db>"]
    for i in range(1, n + 1):
        parts.append(f"<{request}><name>{request}{i}</name><patient>Patient{i}</patient>"
                     f"<{location_field}>Location{i}</{location_field}></{request}>")
    for i in range(1, n + 1):
        parts.append(f"<Location><name>Location{i}</name><patient>Patient{i}</patient></Location>")
    parts.append("<Location><name>Kitchen</name><patient></patient></Location>")
    for i in range(1, n + 1):
        parts.append(f"<Patient><name>Patient{i}</name><can_fetch>true</can_fetch><can_open>true</can_open></Patient>")
    parts.append("</world_db>")
    return "\n".join(parts) + "\n"


def delivery_world(n: int) -> str:
    return food_world(n, "Delivery", "delivery_location")


def pickup_world(n: int) -> str:
    return food_world(n, "Pickup", "pickup_location")


def vital_signs_world(n: int) -> str:
    parts = ["<world_db>"]
    for i in range(n):
        parts.append(f"<Room><name>Room{i}</name><is_occupied>true</is_occupied>"
                     f"<patients>Patient{2 * i + 1},Patient{2 * i + 2}</patients></Room>")
    parts.append("<Room><name>SanitizationRoom</name><is_occupied>false</is_occupied><patients></patients></Room>")
    for p in range(1, 2 * n + 1):
        # every patient has one condition that some CollectVitalSigns method handles
        infectious, diabetes, surgical = p % 3 == 0, p % 3 == 1, p % 3 == 2 or p % 5 == 0
        parts.append(f"<Patient><name>Patient{p}</name><infectious_disease>{str(infectious).lower()}</infectious_disease>"
                     f"<diabetes>{str(diabetes).lower()}</diabetes><post_surgical>{str(surgical).lower()}</post_surgical>"
                     f"<available>true</available><checked>false</checked></Patient>")
    parts.append("</world_db>")
    return "\n".join(parts) + "\n"


def kitchen_world(n: int) -> str:
    """The kitchen alone, initially not busy (the sequence's n visits all go there)."""
    return "<world_db>\n<Location><name>Kitchen</name><is_busy>false</is_busy></Location>\n</world_db>\n"


WORLDS = {"delivery": delivery_world, "pickup": pickup_world, "vital-signs": vital_signs_world,
          "coupled": delivery_world, "coupled-sequence": kitchen_world}

# the sequence's methods test what the earlier visits left: (method, precondition added)
SEQUENCE_PRECONDITIONS = {"food-pickup": "(not (busy ?l))", "food-pickup-mark": "(not (busy ?l))"}


def coupled_domain(hddl: Path, out_dir: Path) -> Path:
    """The delivery domain with the shared ``busy`` fact and the methods that set and clear it."""
    text = hddl.read_text(encoding="utf-8")
    text = text.replace("\t(:predicates\n", "\t(:predicates\n" + COUPLED_PREDICATE, 1)
    end = text.rindex(")")
    out = out_dir / "coupled.hddl"
    out.write_text(text[:end] + COUPLED_DOMAIN + text[end:], encoding="utf-8")
    return out


def sequence_domain(hddl: Path, out_dir: Path) -> Path:
    """The coupled domain with the preconditions of ``SEQUENCE_PRECONDITIONS``."""
    path = coupled_domain(hddl, out_dir)
    text = path.read_text(encoding="utf-8")
    for method, precondition in SEQUENCE_PRECONDITIONS.items():
        head = f"(:method {method}\n\t\t:parameters (?r - robot ?l - location)\n\t\t:task (GetFood ?r ?l)\n"
        assert head in text, f"{method} not found in {hddl}"
        text = text.replace(head, f"{head}\t\t:precondition (and {precondition})\n", 1)
    path.write_text(text, encoding="utf-8")
    return path


SEQUENCE_GROUP = 25  # tasks per subgoal: a flat annotation of a thousand children is too deep to parse


def sequence_goal_model(n: int) -> str:
    """Root ``[G2;G3;...]``: the kitchen query, then subgoals of ``SEQUENCE_GROUP`` GetFood tasks
    each, ``[AT1;AT2;...]``: n GetFood tasks in one sequence."""
    nodes: list[dict] = []
    links: list[dict] = []

    def node(text: str, kind: str, props: dict, parent: dict | None) -> dict:
        uid = f"00000000-0000-4000-8000-{len(nodes):012d}"
        nodes.append({"id": uid, "text": text, "type": kind, "x": 100 + 50 * len(nodes), "y": 60,
                      "customProperties": {"Description": "", **props}})
        if parent is not None:
            links.append({"id": f"00000000-0000-4000-9000-{len(links):012d}", "type": "istar.AndRefinementLink",
                          "source": uid, "target": parent["id"]})
        return nodes[-1]

    groups = [range(k, min(k + SEQUENCE_GROUP, n + 1)) for k in range(1, n + 1, SEQUENCE_GROUP)]
    subgoals = [f"G{3 + i}" for i in range(len(groups))]
    root = node(f"G1: Serve The Kitchen In Turn [{';'.join(['G2'] + subgoals)}]", "istar.Goal", {}, None)
    node("G2: Fetch Kitchen Location", "istar.Goal",
         {"GoalType": "Query", "QueriedProperty": 'world_db->select(l:Location | l.name = "Kitchen")',
          "Controls": "kitchen_loc : Location"}, root)
    for goal, group in zip(subgoals, groups):
        ann = f" [{';'.join(f'AT{k}' for k in group)}]" if len(group) > 1 else ""
        sub = node(f"{goal}: Visit The Kitchen{ann}", "istar.Goal", {"Monitors": "kitchen_loc"}, root)
        for k in group:
            node(f"AT{k}: GetFood", "istar.Task", {"Location": "kitchen_loc"}, sub)
    gm = {"actors": [{"id": "00000000-0000-4000-7000-000000000000", "text": "Kitchen", "type": "istar.Actor",
                      "x": 40, "y": 20, "customProperties": {"Description": ""}, "nodes": nodes}],
          "orphans": [], "dependencies": [], "links": links, "display": {}, "tool": "pistar.2.0.0", "istar": "2.0",
          "saveDate": "Sat, 22 Nov 2025 12:00:00 GMT",
          "diagram": {"width": 200 + 50 * len(nodes), "height": 400, "customProperties": {"Description": ""}}}
    return json.dumps(gm, indent=1) + "\n"


def _sequence_files(n: int, config: dict, hddl: Path, out_dir: Path) -> tuple[Path, Path]:
    """The domain and goal model of the coupled-sequence family; ``config`` gets its mappings."""
    config["type_mapping"] = [{"hddl_type": "location", "ocl_type": "Location"}]
    config["var_mapping"] = [{"task_id": f"AT{k}", "map": [{"gm_var": "kitchen_loc", "hddl_var": "?l"}]}
                             for k in range(1, n + 1)]
    config["semantic_mapping"] = [COUPLED_MAPPING]
    gm = out_dir / f"coupled-sequence-{n}.gm.json"
    gm.write_text(sequence_goal_model(n), encoding="utf-8")
    return sequence_domain(hddl, out_dir), gm


def generate(family: str, n: int, out_dir: Path) -> tuple[Path, Path, Path]:
    """Write the world and a configuration for it; return (hddl, goal model, configuration)."""
    folder, template, gm_name = FAMILIES[family]
    src = REFERENCE / folder
    out_dir.mkdir(parents=True, exist_ok=True)
    world = out_dir / f"{family}-{n}.xml"
    world.write_text(WORLDS[family](n), encoding="utf-8")
    config = json.loads((src / "configuration" / template).read_text(encoding="utf-8"))
    config["world_db"]["path"] = str(world.resolve())
    config["output"]["file_path"] = str((out_dir / f"{family}-{n}.out.json").resolve())
    hddl = next((src / "hddl").glob("*.hddl"))
    gm = src / "gm" / gm_name
    if family == "coupled":
        config["semantic_mapping"].append(COUPLED_MAPPING)
        hddl = coupled_domain(hddl, out_dir)
    elif family == "coupled-sequence":
        hddl, gm = _sequence_files(n, config, hddl, out_dir)
    cfg = out_dir / f"{family}-{n}.json"
    cfg.write_text(json.dumps(config, indent=2), encoding="utf-8")
    return hddl, gm, cfg


def main(argv: list[str]) -> int:
    if len(argv) != 3 or argv[0] not in FAMILIES or not argv[1].isdigit():
        print(__doc__, file=sys.stderr)
        return 2
    source = REFERENCE / FAMILIES[argv[0]][0]
    if not source.is_dir():
        print(f"error: {source}: not found; the families are made from the reference corpus's missions: "
              "put it at ../shared/reference or set MUTROSE_REFERENCE", file=sys.stderr)
        return 2
    hddl, gm, cfg = generate(argv[0], int(argv[1]), Path(argv[2]))
    print(hddl, gm, cfg, sep="\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
