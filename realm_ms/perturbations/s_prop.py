"""5 S-PROP: the instruction refers to the object by object properties (colour, shape, material, size) instead of the name."""

from realm_ms.perturbations.semantic import InstructionVariant


class SProp(InstructionVariant):
    pid = 5
    name = "S-PROP"
