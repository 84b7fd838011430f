"""0 Default: the unperturbed task (the empty composition)."""

from realm_ms.tasks.perturbation import Perturbation


class Default(Perturbation):
    pid = 0
    name = "Default"
    acts_on = "nothing"
    ranges = "-"
