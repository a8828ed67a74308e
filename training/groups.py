"""The background of each development photo, for leave-one-background-out validation
(no dependencies: the training scenes and scripts/lobo.py both read it).

Read off the photos: the split is ordered by background, and a colour rule does not
separate pale wood from white board (models/README.md).
"""

SIMPLE_GROUPS = {"white": range(0, 18), "wood": range(18, 30), "blue": range(30, 40)}
GROUPS = ("white", "wood", "blue", "hard")


def background_group(set_name: str, name: str) -> str:
    """`hard` for the textured set; `white`, `wood` or `blue` for `simple`."""
    if set_name == "hard":
        return "hard"
    number = int(name)
    for group, numbers in SIMPLE_GROUPS.items():
        if number in numbers:
            return group
    raise ValueError(f"simple/{name} has no background group")
