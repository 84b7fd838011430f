"""Semantics and plausible sizes for real-mesh categories, and name -> category inference.

Procedural categories already carry exact semantics (``asset_pipeline.procedural.REGISTRY``); this
table adds categories that only real meshes provide and the keyword rules that map file/folder names
(YCB, LIBERO, robosuite, user folders) onto categories.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from asset_pipeline.semantics import Semantics


@dataclass(frozen=True)
class CategoryInfo:
    semantics: Semantics
    density: float  # effective kg/m^3 over the solid volume
    size: tuple[float, float]  # plausible largest extent (m)
    friction: float = 0.6
    mass_range: tuple[float, float] = (0.005, 3.0)


def _s(cat, material, shapes=(), uses=(), fact=None, seen=True, theme="misc", names=()):
    return Semantics(category=cat, material=material, shapes=tuple(shapes), uses=tuple(uses), fact=fact, seen=seen, theme=theme, names=tuple(names))


# Categories contributed only by real meshes (sizes are typical real-world largest extents).
EXTRA: dict[str, CategoryInfo] = {
    "sugar_box": CategoryInfo(_s("sugar_box", "cardboard", ["rectangular"], ["something that holds sugar"], "sweetens coffee", theme="food", names=["box of sugar"]), 400, (0.12, 0.2)),
    "pudding_box": CategoryInfo(_s("pudding_box", "cardboard", ["rectangular", "small"], ["a dessert mix"], "is made by adding milk", theme="food", names=["pudding box"]), 400, (0.08, 0.14)),
    "gelatin_box": CategoryInfo(_s("gelatin_box", "cardboard", ["rectangular", "small"], ["a dessert mix"], "wobbles when set", theme="food", names=["gelatin box"]), 400, (0.07, 0.12)),
    "mustard_bottle": CategoryInfo(_s("mustard_bottle", "plastic", ["tall", "squeezable"], ["something to squeeze onto a hot dog"], "is made from mustard seeds", theme="containers", names=["mustard bottle", "mustard"]), 600, (0.15, 0.22)),
    "bleach_bottle": CategoryInfo(_s("bleach_bottle", "plastic", ["tall"], ["something to clean with"], "must not be mixed with other cleaners", theme="containers", names=["bleach bottle", "cleanser"]), 500, (0.2, 0.28)),
    "pitcher": CategoryInfo(_s("pitcher", "plastic", ["tall", "with a handle"], ["something to pour water from"], "holds enough for several glasses", theme="containers"), 200, (0.2, 0.3)),
    "power_drill": CategoryInfo(_s("power_drill", "plastic", ["L-shaped"], ["something to drill holes with"], "runs on a rechargeable battery", seen=False, theme="non_droid", names=["power drill", "drill"]), 600, (0.18, 0.25)),
    "scissors": CategoryInfo(_s("scissors", "metal", ["long", "flat"], ["something to cut paper with"], "should be passed handle first", theme="stationery"), 1500, (0.15, 0.22)),
    "clamp": CategoryInfo(_s("clamp", "plastic", ["C-shaped"], ["something to hold pieces together"], "is used in woodworking", seen=False, theme="non_droid"), 800, (0.1, 0.22)),
    "soccer_ball": CategoryInfo(_s("soccer_ball", "leather", ["round", "spherical"], ["something to kick"], "is played in the World Cup", theme="sports", names=["soccer ball", "ball"]), 150, (0.12, 0.15)),
    "softball": CategoryInfo(_s("softball", "leather", ["round", "spherical"], ["something to throw and catch"], "is bigger than a baseball", theme="sports", names=["softball", "ball"]), 450, (0.09, 0.1)),
    "strawberry": CategoryInfo(_s("strawberry", "organic", ["small", "conical"], ["something to eat"], "has its seeds on the outside", theme="food"), 900, (0.03, 0.05)),
    "chain": CategoryInfo(_s("chain", "metal", ["long", "flexible"], ["something to lock a bike with"], "is made of linked rings", seen=False, theme="non_droid"), 3000, (0.2, 0.6)),
    "foam_brick": CategoryInfo(_s("foam_brick", "foam", ["rectangular", "soft"], ["a soft toy block"], "is light and squishy", theme="toys", names=["foam brick"]), 100, (0.05, 0.08)),
    "marble": CategoryInfo(_s("marble", "glass", ["round", "small"], ["a toy to roll"], "is made of glass", seen=False, theme="non_droid"), 2500, (0.01, 0.04)),
    "peg_board": CategoryInfo(_s("peg_board", "wood", ["flat", "with holes"], ["a dexterity test"], "has nine holes", seen=False, theme="non_droid", names=["peg board"]), 600, (0.1, 0.2)),
    "toy_airplane_part": CategoryInfo(_s("toy_airplane_part", "plastic", ["irregular"], ["a piece of a toy kit"], "snaps together with other parts", seen=False, theme="non_droid", names=["toy part"]), 800, (0.03, 0.2)),
    "toy_brick": CategoryInfo(_s("toy_brick", "plastic", ["rectangular", "studded"], ["something to build with"], "clicks onto other bricks", theme="toys", names=["toy brick", "duplo brick"]), 600, (0.03, 0.07)),
    "rubiks_cube": CategoryInfo(_s("rubiks_cube", "plastic", ["cube"], ["a puzzle to solve"], "has 43 quintillion positions", seen=False, theme="non_droid", names=["Rubik's cube", "puzzle cube"]), 600, (0.055, 0.06)),
    "bread": CategoryInfo(_s("bread", "organic", ["oval"], ["something to eat", "something to make a sandwich with"], "is baked in an oven", theme="food"), 250, (0.08, 0.3)),
    "butter": CategoryInfo(_s("butter", "cardboard", ["rectangular", "small"], ["something to spread on bread"], "is made from cream", theme="food"), 900, (0.08, 0.14)),
    "cream_cheese": CategoryInfo(_s("cream_cheese", "cardboard", ["rectangular", "small"], ["something to spread on a bagel"], "is kept in the fridge", theme="food", names=["cream cheese"]), 900, (0.08, 0.14)),
    "salad_dressing": CategoryInfo(_s("salad_dressing", "plastic", ["tall", "bottle-shaped"], ["something to pour on salad"], "is shaken before use", theme="containers", names=["salad dressing", "bottle"]), 700, (0.15, 0.22)),
    "bbq_sauce": CategoryInfo(_s("bbq_sauce", "plastic", ["tall", "bottle-shaped"], ["something to put on grilled meat"], "is smoky and sweet", theme="containers", names=["barbecue sauce", "bottle"]), 700, (0.15, 0.22)),
    "orange_juice": CategoryInfo(_s("orange_juice", "cardboard", ["rectangular", "tall"], ["something to drink at breakfast"], "is squeezed from oranges", theme="containers", names=["orange juice", "carton"]), 700, (0.12, 0.22)),
    "popcorn": CategoryInfo(_s("popcorn", "cardboard", ["rectangular"], ["a snack for the cinema"], "pops when heated", theme="food"), 200, (0.1, 0.2)),
    "macaroni_and_cheese": CategoryInfo(_s("macaroni_and_cheese", "cardboard", ["rectangular"], ["something to cook for dinner"], "is pasta with cheese sauce", theme="food", names=["macaroni and cheese"]), 400, (0.1, 0.2)),
    "chocolate_pudding": CategoryInfo(_s("chocolate_pudding", "cardboard", ["rectangular", "small"], ["a dessert"], "is made from cocoa", theme="food", names=["chocolate pudding"]), 400, (0.06, 0.12)),
    "ramekin": CategoryInfo(_s("ramekin", "ceramic", ["round", "small", "hollow"], ["something to bake a dessert in"], "is used for crème brûlée", theme="containers"), 600, (0.07, 0.12)),
    "basket": CategoryInfo(_s("basket", "plastic", ["rectangular", "hollow"], ["something to carry things in", "a container"], "is woven or moulded", theme="containers"), 150, (0.2, 0.35), mass_range=(0.05, 1.0)),
    "rack": CategoryInfo(_s("rack", "wood", ["rectangular"], ["something to hold dishes or bottles"], "keeps things upright", seen=False, theme="non_droid"), 200, (0.15, 0.4), mass_range=(0.05, 2.0)),
    "moka_pot": CategoryInfo(_s("moka_pot", "metal", ["octagonal", "with a handle"], ["something to make coffee in"], "was invented in Italy", seen=False, theme="non_droid", names=["moka pot", "coffee maker"]), 500, (0.12, 0.22)),
    "desk_caddy": CategoryInfo(_s("desk_caddy", "wood", ["rectangular", "hollow"], ["something to hold pens"], "keeps a desk tidy", seen=False, theme="non_droid", names=["desk caddy", "pen holder"]), 200, (0.1, 0.25)),
    "storage_box": CategoryInfo(_s("storage_box", "plastic", ["rectangular", "hollow"], ["something to store things in"], "stacks on a shelf", theme="containers", names=["storage box", "box"]), 150, (0.15, 0.35)),
    "bowl_drainer": CategoryInfo(_s("bowl_drainer", "plastic", ["round", "with holes"], ["something to drain washed vegetables in"], "lets water run out", seen=False, theme="non_droid", names=["colander"]), 150, (0.15, 0.3)),
    "electric_switch": CategoryInfo(_s("electric_switch", "plastic", ["flat", "rectangular"], ["something to turn the lights on"], "closes an electric circuit", seen=False, theme="non_droid", names=["light switch", "switch"]), 800, (0.07, 0.13)),
    "power_outlet": CategoryInfo(_s("power_outlet", "plastic", ["flat", "rectangular"], ["something to plug a charger into"], "supplies electricity", seen=False, theme="non_droid", names=["power outlet", "socket"]), 800, (0.07, 0.13)),
    "geometric_shape": CategoryInfo(_s("geometric_shape", "plastic", ["geometric"], ["something to stack", "a test object"], "comes from the RGB-stacking benchmark", seen=False, theme="non_droid", names=["shape", "object"]), 700, (0.04, 0.08)),
    "abstract_object": CategoryInfo(_s("abstract_object", "plastic", ["irregular"], ["a random test object"], "has no everyday meaning", seen=False, theme="non_droid", names=["object"]), 700, (0.03, 0.08)),
    "teddy_bear": CategoryInfo(_s("teddy_bear", "fabric", ["soft"], ["a toy to cuddle"], "is named after Theodore Roosevelt", theme="toys", names=["teddy bear"]), 200, (0.1, 0.3)),
    "jenga_block": CategoryInfo(_s("jenga_block", "wood", ["rectangular", "long"], ["something to stack"], "is pulled from a tower in a game", theme="toys", names=["wooden block", "jenga block"]), 650, (0.07, 0.08)),
    # Meta-World / Gymnasium-Robotics / Genesis meshes (asset_pipeline/sources/sim_packages.py).
    "hockey_puck": CategoryInfo(_s("hockey_puck", "rubber", ["round", "flat", "disc-shaped"], ["something to hit with a hockey stick"], "is frozen before ice hockey games", seen=False, theme="non_droid", names=["hockey puck", "puck"]), 1200, (0.07, 0.1)),
    "thermos": CategoryInfo(_s("thermos", "metal", ["cylindrical", "tall"], ["something to keep drinks hot"], "has a vacuum between two walls", seen=False, theme="non_droid", names=["thermos", "flask"]), 400, (0.15, 0.3)),
    "electric_plug": CategoryInfo(_s("electric_plug", "plastic", ["small", "with prongs"], ["something to plug into a socket"], "carries electricity to a device", seen=False, theme="non_droid", names=["plug", "electric plug"]), 900, (0.04, 0.08)),
    "peg_ring": CategoryInfo(_s("peg_ring", "plastic", ["ring", "round", "with a handle"], ["something to slide onto a peg"], "comes from the Meta-World assembly task", seen=False, theme="non_droid", names=["ring", "peg ring"]), 700, (0.08, 0.14)),
    "dial_knob": CategoryInfo(_s("dial_knob", "plastic", ["round", "flat"], ["something to turn"], "sets a value by rotation", seen=False, theme="non_droid", names=["dial", "knob"]), 800, (0.06, 0.1)),
    "nail": CategoryInfo(_s("nail", "metal", ["long", "thin", "pointed"], ["something to hammer into wood"], "is driven in with a hammer", seen=False, theme="non_droid"), 3000, (0.05, 0.13)),
    "golf_club_head": CategoryInfo(_s("golf_club_head", "metal", ["irregular", "heavy"], ["the striking end of a golf club"], "hits the golf ball", seen=False, theme="non_droid", names=["golf club head", "club head"]), 2000, (0.08, 0.13)),
    "hammer_head": CategoryInfo(_s("hammer_head", "metal", ["T-shaped"], ["the striking part of a hammer"], "is the heavy end of a hammer", seen=False, theme="non_droid", names=["hammer head"]), 3000, (0.08, 0.15)),
    "kettle": CategoryInfo(_s("kettle", "metal", ["round", "with a handle", "with a spout"], ["something to boil water in"], "whistles when the water boils", seen=False, theme="non_droid"), 150, (0.18, 0.3), mass_range=(0.2, 1.5)),
    "stove_knob": CategoryInfo(_s("stove_knob", "plastic", ["round", "small"], ["something to turn a burner on"], "controls the flame of a stove", seen=False, theme="non_droid", names=["stove knob", "knob"]), 900, (0.04, 0.1)),
    "dragon_figurine": CategoryInfo(_s("dragon_figurine", "plastic", ["irregular", "dragon-shaped"], ["a decoration"], "shows a creature from legends", seen=False, theme="non_droid", names=["dragon", "figurine"]), 900, (0.08, 0.2)),
    "bunny_figurine": CategoryInfo(_s("bunny_figurine", "ceramic", ["round", "rabbit-shaped"], ["a decoration"], "is the famous Stanford bunny scan", seen=False, theme="non_droid", names=["bunny", "rabbit figurine"]), 1200, (0.06, 0.15)),
    "cutting_board": CategoryInfo(_s("cutting_board", "wood", ["flat", "rectangular"], ["something to chop vegetables on"], "protects the counter from the knife", seen=False, theme="non_droid", names=["cutting board", "chopping board"]), 700, (0.2, 0.35)),
    "camera": CategoryInfo(_s("camera", "plastic", ["boxy", "with a lens"], ["something to take photos with"], "captures light on a sensor", seen=False, theme="non_droid"), 600, (0.08, 0.15)),
    "bolt": CategoryInfo(_s("bolt", "metal", ["hexagonal", "threaded"], ["something to fasten with a nut"], "is tightened with a wrench", seen=False, theme="non_droid"), 7800, (0.03, 0.08), mass_range=(0.005, 0.5)),
    "nut": CategoryInfo(_s("nut", "metal", ["hexagonal", "small", "with a hole"], ["something to screw onto a bolt"], "has six sides", seen=False, theme="non_droid", names=["nut", "hex nut"]), 7800, (0.02, 0.05), mass_range=(0.003, 0.3)),
    "wooden_ball": CategoryInfo(_s("wooden_ball", "wood", ["round", "spherical"], ["something to roll"], "is turned on a lathe", seen=False, theme="non_droid", names=["wooden ball", "ball"]), 700, (0.04, 0.08)),
    "stirrer": CategoryInfo(_s("stirrer", "metal", ["long", "thin"], ["something to stir a drink with"], "mixes sugar into coffee", seen=False, theme="non_droid", names=["stirrer", "stir stick"]), 2000, (0.12, 0.2)),
    "toy_airplane": CategoryInfo(_s("toy_airplane", "plastic", ["winged"], ["a toy that pretends to fly"], "is a small model of a real plane", seen=False, theme="non_droid", names=["toy airplane", "airplane", "plane"]), 300, (0.1, 0.25)),
    "toy_boat": CategoryInfo(_s("toy_boat", "wood", ["boat-shaped"], ["a toy that floats"], "is a small model of a real boat", seen=False, theme="non_droid", names=["toy boat", "boat"]), 400, (0.1, 0.25)),
    "toy_tank": CategoryInfo(_s("toy_tank", "plastic", ["boxy", "with a turret"], ["a toy vehicle"], "is a small model of an army tank", seen=False, theme="non_droid", names=["toy tank", "tank"]), 600, (0.1, 0.2)),
    "basketball": CategoryInfo(_s("basketball", "rubber", ["round", "spherical"], ["something to throw through a hoop"], "is bounced while dribbling", seen=False, theme="non_droid", names=["basketball", "ball"]), 150, (0.06, 0.12)),
    "fmb_piece": CategoryInfo(_s("fmb_piece", "plastic", ["geometric", "angular"], ["a piece to insert into a board"], "comes from the Functional Manipulation Benchmark", seen=False, theme="non_droid", names=["block", "piece"]), 700, (0.08, 0.16)),
    "handle_set": CategoryInfo(_s("handle_set", "metal", ["irregular"], ["a handle to pull"], "is fixed to cabinet doors", seen=False, theme="non_droid", names=["handles"]), 1500, (0.05, 0.15)),
}

# Name keyword -> category, checked in order (first match wins). Longest/most specific first.
RULES: tuple[tuple[str, str], ...] = (
    (r"master_chef_can|tomato_soup_can|tuna_fish_can|potted_meat_can|alphabet_soup|tomato_sauce|soup|\bcan\b", "food_can"),
    (r"cracker", "cracker_box"), (r"sugar", "sugar_box"), (r"pudding_box", "pudding_box"), (r"gelatin", "gelatin_box"),
    (r"mustard", "mustard_bottle"), (r"bleach", "bleach_bottle"), (r"windex|spray", "spray_bottle"), (r"pitcher", "pitcher"),
    (r"ketchup", "ketchup_bottle"), (r"bbq", "bbq_sauce"), (r"salad_dressing", "salad_dressing"), (r"orange_juice", "orange_juice"),
    (r"chocolate_pudding", "chocolate_pudding"), (r"macaroni", "macaroni_and_cheese"), (r"popcorn", "popcorn"),
    (r"cream_cheese", "cream_cheese"), (r"butter", "butter"), (r"cookie", "bag_of_cookies"), (r"milk", "milk_carton"),
    (r"cereal", "cereal_box"), (r"bread", "bread"),
    (r"skillet_lid|\blid\b", "lid"), (r"frypan|skillet|frying_pan", "frying_pan"), (r"ramekin", "ramekin"), (r"drainer", "bowl_drainer"),
    (r"bowl", "bowl"), (r"plate", "plate"), (r"mug", "mug"), (r"cups|\bcup\b", "cup"), (r"wine_bottle", "wine_bottle"),
    (r"bottle", "water_bottle"), (r"fork", "fork"), (r"spoon", "spoon"), (r"knife", "knife"), (r"spatula", "spatula"),
    (r"drill", "power_drill"), (r"wood_block|colored_wood_blocks|jenga", "toy_block"), (r"scissors", "scissors"), (r"padlock|lock", "padlock"),
    (r"marker", "marker"), (r"wrench", "wrench"), (r"screwdriver", "screwdriver"), (r"hammer", "hammer"), (r"clamp", "clamp"),
    (r"soccer", "soccer_ball"), (r"softball", "softball"), (r"baseball", "baseball"), (r"tennis", "tennis_ball"),
    (r"racquetball", "rubber_ball"), (r"golf", "golf_ball"), (r"chain", "chain"), (r"foam_brick", "foam_brick"), (r"dice", "dice"),
    (r"marble", "marble"), (r"peg", "peg_board"), (r"airplane", "toy_airplane_part"), (r"duplo|lego", "toy_brick"),
    (r"rubik", "rubiks_cube"), (r"banana", "banana"), (r"strawberry", "strawberry"), (r"apple", "apple"), (r"lemon", "lemon"),
    (r"peach", "peach"), (r"pear", "pear"), (r"orange", "orange"), (r"plum", "plum"), (r"sponge", "sponge"),
    (r"basket", "basket"), (r"rack|shelf", "rack"), (r"moka", "moka_pot"), (r"caddy", "desk_caddy"), (r"storage_box", "storage_box"),
    (r"book", "book"), (r"tray", "tray"), (r"switch", "electric_switch"), (r"outlet", "power_outlet"), (r"teddy", "teddy_bear"),
    (r"duck", "rubber_duck"), (r"domino", "domino"), (r"cube", "cube"), (r"handles", "handle_set"), (r"box", "box"),
)


def infer_category(name: str) -> str | None:
    n = name.lower().replace("-", "_").replace(" ", "_")
    for pat, cat in RULES:
        if re.search(pat, n):
            return cat
    return None


@lru_cache(maxsize=None)
def category_info(category: str) -> CategoryInfo:
    """Semantics/size/density for any category: procedural registry first, then :data:`EXTRA`,
    then a neutral default for unknown user categories (treated as unseen)."""
    from asset_pipeline.procedural import REGISTRY, make_object

    if category in REGISTRY:
        c = REGISTRY[category]
        ext = [float(make_object(category, s).extents.max()) for s in range(4)]
        sem = Semantics(category=category, shapes=c.shapes, material=c.material, uses=c.uses, fact=c.fact, seen=c.seen, theme=c.theme,
                        names=c.names or (category.replace("_", " "),))
        return CategoryInfo(sem, c.density, (min(ext), max(ext)), c.friction, c.mass_range)
    if category in EXTRA:
        return EXTRA[category]
    return CategoryInfo(_s(category, "unknown", seen=False, theme="non_droid", names=[category.replace("_", " ")]), 500, (0.03, 0.3))


def nearest_colour_names(rgb: np.ndarray, k: int = 1) -> list[str]:
    """Palette names closest to an average RGB in [0, 1] (estimated colours for real meshes)."""
    from asset_pipeline.procedural.colors import PALETTE

    names = [n for n in PALETTE if n != "clear"]
    d = [float(np.linalg.norm(np.asarray(PALETTE[n]) - rgb)) for n in names]
    return [names[i] for i in np.argsort(d)[:k]]
