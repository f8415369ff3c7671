%
O0008 (08-peck)
G21 G17 G90 G40 G49 G80 G94
T1 M6
G43 H1
S1000 M3
G0 X0 Y0 Z20.
(hole 1: pecks of 4, full retract to R2, approach 2 above the depth reached)
G0 X20. Y20.
G0 Z2.
G1 Z-4. F150
G0 Z2.
G0 Z-2.
G1 Z-8. F150
G0 Z2.
G0 Z-6.
G1 Z-10. F150
G0 Z2.
G0 Z20.
(hole 2: pecks of 5, 4, 3 - 1 less each time - retracting at the plunging feed)
G0 X40. Y20.
G0 Z2.
G1 Z-5. F150
G1 Z2. F150
G0 Z-3.
G1 Z-9. F150
G1 Z2. F150
G0 Z-7.
G1 Z-10. F150
G1 Z2. F150
G0 Z20.
M5
M30
%
