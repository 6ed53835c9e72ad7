"""Dynamic-data rows the model tests share (tests/models, tests/io): each written once.

Importable from any test module: ``tests/`` is on ``sys.path`` (pytest's default
``prepend`` import mode for the rootdir conftest)."""

# fmt: off
#: IEEEG1 (tg_con type 3; columns as stabctl.models.governors.GOVERNOR declares them):
#: K1 + K2, K3 + K4, K5 + K6 = 0.3, 0.6, 0.1 (columns 21, 23, 24), so Pm = gate at rest
IEEEG1 = [3, 1, 1, 20, 0.95, 0.2, 0.1, 0, 0.1, 0, 0, 0, 0, 8.72, 0.5, -1, 0, 0, 0, 0, 0.3, 0,
          0.6, 0.1]
#: EXST1 (exc_con type 4): TR KA TA TB TC Vrmax Vrmin VImax VImin (columns 3-11), KC (17),
#: KF TF (21-22)
EXST1 = [4, 1, 0.02, 50, 0.02, 0.02, 0.1, 4.0, -3.0, 0.2, -0.2, 0, 0, 0, 0, 0, 0.1, 0, 0, 0,
         0.01, 1.0]
# fmt: on
