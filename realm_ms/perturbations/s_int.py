"""9 S-INT: the instruction refers to the object by internal knowledge (facts about the object) instead of the name."""

from realm_ms.perturbations.semantic import InstructionVariant


class SInt(InstructionVariant):
    pid = 9
    name = "S-INT"
