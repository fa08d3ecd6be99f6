"""The benchmark bicycle (Meijaard, Papadopoulos, Ruina, Schwab 2007): the paper's linearised
equations (`meijaard`)."""
