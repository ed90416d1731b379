"""Shared utilities below every other folder: rotations and frames (`spatial`), files
written whole or not at all (`atomic`), strict JSON text (`jsontext`), numbers as the
text outputs print them (`formatting`), immutable instances without a frozen
dataclass's start-up cost (`frozen`). They import nothing of mbody but `errors`."""
