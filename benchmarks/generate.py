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


WORLDS = {"delivery": delivery_world, "pickup": pickup_world, "vital-signs": vital_signs_world,
          "coupled": delivery_world}


def coupled_domain(hddl: Path, out_dir: Path) -> Path:
    """The delivery domain with the shared ``busy`` fact and the methods that set and clear it."""
    text = hddl.read_text(encoding="utf-8")
    text = text.replace("\t(:predicates\n", "\t(:predicates\n" + COUPLED_PREDICATE, 1)
    end = text.rindex(")")
    out = out_dir / "coupled.hddl"
    out.write_text(text[:end] + COUPLED_DOMAIN + text[end:], encoding="utf-8")
    return out


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
    if family == "coupled":
        config["semantic_mapping"].append(COUPLED_MAPPING)
        hddl = coupled_domain(hddl, out_dir)
    cfg = out_dir / f"{family}-{n}.json"
    cfg.write_text(json.dumps(config, indent=2), encoding="utf-8")
    return hddl, src / "gm" / gm_name, cfg


def main(argv: list[str]) -> int:
    if len(argv) != 3 or argv[0] not in FAMILIES:
        print(__doc__, file=sys.stderr)
        return 2
    hddl, gm, cfg = generate(argv[0], int(argv[1]), Path(argv[2]))
    print(hddl, gm, cfg, sep="\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
