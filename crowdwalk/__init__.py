"""crowdwalk: crowds of walking people that plan their footsteps."""

from crowdwalk.errors import InfeasibleError, InputError

__all__ = ["InputError", "InfeasibleError", "__version__"]
__version__ = "0.1.0"
