(trap: #3000 in IF ... THEN stops the program)
G21 G90 G17
#100=2
IF [#100 GT 1] THEN #3000=12 (TOO MANY PARTS)
G0 X2
M30
