"""The ``hop-impedance`` command (placeholder until the sub-commands land)."""


def main(argv=None) -> int:
    print("hop-impedance: sub-commands are being built")
    return 0
