"""7 S-MO: the instruction refers to the object by multi-object references (the object described relative to others in the scene)."""

from realm_ms.perturbations.semantic import InstructionVariant


class SMo(InstructionVariant):
    pid = 7
    name = "S-MO"
