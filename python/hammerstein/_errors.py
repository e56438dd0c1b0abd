"""The package's exceptions."""


class HammersteinError(Exception):
    """A fit, an identification or a simulation failed (the crate's message)."""


class InputError(HammersteinError, ValueError):
    """Bad input: NaN, mismatched lengths, a wrong dtype or shape, an unknown option.

    A ``ValueError`` (and a :class:`HammersteinError`), so ``except ValueError`` catches it.
    """
