# Convoyeur simple (thèse d'Allahham, 2008, chapitre 4.3.1) : les textes de
# l'installation en français.

signal-a = Palette en A, l'entrée du convoyeur
signal-b = Palette en B, la fin du convoyeur (le b de la thèse)
signal-m = Convoyeur en mouvement (sa chute est le s de la thèse, sa montée r)
signal-d = Bouton d'ordre (le d de la thèse)
signal-P = Pousseur : dépose une palette en A
signal-CV = Moteur du convoyeur

element-conveyor = Convoyeur
element-panel = Pupitre
part-conveyor = Convoyeur
part-order_button = Bouton d'ordre
item-pallet = palette

constraint-CSc1 = pas de palette poussée sur l'entrée tant qu'une autre y est : elles se heurtent
off-P = le pousseur reste rentré
off-CV = le convoyeur s'arrête ; la palette reste où elle est

scenario-reference = Convoyeur simple : trois palettes sans défaut
scenario-thesis-permanent-block = Convoyeur simple : palette bloquée à 4 s (thèse, cas 2)
scenario-thesis-intermittent = Convoyeur simple : deux arrêts de 1 s (thèse, cas 1)
scenario-thesis-short-stop = Convoyeur simple : un arrêt de 1,5 s (thèse, cas 3)
scenario-thesis-slowdown = Convoyeur simple : tapis ralenti à 80 % (thèse, ralentissement)

task-transfer = transfert : pousser une palette en A et la porter jusqu'en B (10 s)
