"""Reference tables of validation/CASES.md A2 and A3 (the linear spring-dashpot and the
Hertz-Mindlin restitution closed forms), shared by test_linear_law and test_restitution. One
entry per restitution of TABLE_E."""

# fmt: off
TABLE_E = (0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95, 0.98)
# A2 (linear law): damping ratio; w0 t_c with tension
TABLE_ZETA = (0.59116, 0.45595, 0.35786, 0.28000, 0.21545, 0.16049,
              0.11281, 0.07085, 0.03352, 0.01632, 0.00643)
TABLE_W0TC_TENSION = (3.8951, 3.5299, 3.3644, 3.2725, 3.2172, 3.1829,
                      3.1618, 3.1495, 3.1434, 3.1420, 3.1417)
# A2 without tension: the restitution e_f and w0 t_c
TABLE_E_F = (0.2527, 0.3249, 0.3971, 0.4720, 0.5503, 0.6323,
             0.7182, 0.8081, 0.9020, 0.9505, 0.9801)
TABLE_W0TC_NO_TENSION = (2.3267, 2.4660, 2.5805, 2.6813, 2.7724, 2.8562,
                         2.9342, 3.0073, 3.0763, 3.1094, 3.1288)
# A3 (Hertz-Mindlin): t_c / t_c(elastic), with and without tension
TABLE_TC_TENSION = (1.5107, 1.2959, 1.1949, 1.1342, 1.0934, 1.0640,
                    1.0419, 1.0247, 1.0111, 1.0053, 1.0020)
TABLE_TC_NO_TENSION = (0.7880, 0.8199, 0.8461, 0.8693, 0.8906, 0.9108,
                       0.9305, 0.9502, 0.9711, 0.9830, 0.9916)
# fmt: on
