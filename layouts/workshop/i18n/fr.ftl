# Atelier de fabrication (thèse d'Allahham, 2008, chapitre 4.4) : les textes de
# l'installation en français, lus par la console après les siens. En anglais, la
# console montre les descriptions de plant.ron.

signal-a = Palette en A, l'entrée du convoyeur (où le pousseur la dépose)
signal-b = Palette en B, la fin du convoyeur
signal-mc = Convoyeur en mouvement (détecteur de mouvement : sa chute est le s_c de la thèse, sa montée r_c)
signal-h = Robot au repos, au-dessus de B
signal-R = Robot au poste d'assemblage : la palette déposée
signal-mr = Robot en mouvement (détecteur de mouvement : sa chute est le s_R de la thèse, sa montée r_R)
signal-d = Bouton d'ordre : charger une palette (le d de la thèse)
signal-P = Pousseur : dépose une palette en A
signal-CV = Moteur du convoyeur
signal-RB = Robot : prendre la palette en B et la porter au poste d'assemblage
signal-RH = Robot : revenir au repos au-dessus de B

element-conveyor = Convoyeur
element-robot = Robot
element-panel = Pupitre

part-conveyor = Convoyeur
part-robot = Robot
part-order_button = Bouton d'ordre
item-pallet = palette

constraint-CSw1 = pas de palette poussée sur l'entrée tant qu'une autre y est : elles se heurtent
constraint-CSw2 = robot commandé dans les deux sens à la fois
constraint-CSw3 = le robot saisit la palette en B alors que le convoyeur l'entraîne encore : la palette est arrachée de la pince

off-P = le pousseur reste rentré
off-CV = le convoyeur s'arrête ; les palettes restent où elles sont
off-RB = le robot s'arrête où il est
off-RH = le robot s'arrête où il est

scenario-reference = Atelier : cinq palettes sans défaut
scenario-thesis-scenario-1 = Atelier : scénario 1 de la thèse (convoyeur coincé à 4 s)
scenario-thesis-scenario-2 = Atelier : scénario 2 de la thèse (deux arrêts courts, pas d'alarme)
scenario-thesis-scenario-3 = Atelier : scénario 3 de la thèse (le robot s'arrête, puis définitivement)
scenario-e01-robot-order-stored = Atelier : E01, ordre du robot mémorisé

variant-E01 = Ordre de transfert du robot mémorisé (S) au lieu de non mémorisé (N) dans W5 : RB reste commandé quand l'étape de retour W7 commande RH, le robot est commandé dans les deux sens
variant-E02 = Ordre de retour écrit aussi dans l'étape de transfert (RH dans W5 comme dans W7) : le robot est commandé dans les deux sens à la fois
variant-E03 = Ordre du convoyeur mémorisé (S) au lieu de non mémorisé (N) dans W2 : le convoyeur tourne encore quand le robot saisit la palette en B

task-conveyor = convoyeur et pousseur (tâche 1) : pousser une palette en A et la porter jusqu'en B (3 s)
task-robot = robot (tâche 2) : porter la palette de B au poste d'assemblage (2 s)
