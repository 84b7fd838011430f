"""8 S-AFF: the instruction refers to the object by affordances (what the object is used for) instead of the name."""

from realm_ms.perturbations.semantic import InstructionVariant


class SAff(InstructionVariant):
    pid = 8
    name = "S-AFF"
