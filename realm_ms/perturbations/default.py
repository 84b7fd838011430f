"""0 Default: the unperturbed task (the empty composition)."""

from realm_ms.tasks.perturbation import DEFAULT, Perturbation


class Default(Perturbation):
    pid = 0
    name = DEFAULT
    acts_on = "nothing"
    ranges = "-"
