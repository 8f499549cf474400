# Station de tri (ADEXEC) : les textes de l'installation en français, lus par la
# console après les siens (`signal-<id>` : la description d'un signal). En anglais, la
# console montre les descriptions de plant.ron.

signal-C0 = Caisse en bout du convoyeur d'entrée
signal-C1 = Caisse devant la cellule basse (toute caisse ; une petite caisse est C1 sans C2)
signal-C2 = Grande caisse devant la cellule haute
signal-C3 = Caisse en bout du convoyeur intermédiaire
signal-C4 = Table tournante en position de chargement
signal-C5 = Table tournante en position de déchargement
signal-C6 = Caisse présente sur la table tournante
signal-C7 = Caisse à l'entrée du convoyeur de sortie droit
signal-C8 = Caisse à l'entrée du convoyeur de sortie gauche
signal-C9 = Caisse en bout du convoyeur de sortie droit
signal-C10 = Caisse en bout du convoyeur de sortie gauche
signal-A0 = Moteur du convoyeur d'entrée
signal-A1 = Moteur du convoyeur intermédiaire
signal-A2 = Rouleaux de la table : chargement, et évacuation à gauche en position de déchargement
signal-A3 = Rouleaux de la table : évacuation à droite
signal-A4 = Rotation de la table vers la position de déchargement (monostable : revient au relâchement)
signal-A5 = Moteur du convoyeur de sortie gauche
signal-A6 = Moteur du convoyeur de sortie droit

# Les éléments de l'installation (`element` dans plant.ron : minuscules, espaces en
# tirets).
element-entry-conveyor = Convoyeur d'entrée
element-intermediate-conveyor = Convoyeur intermédiaire
element-left-exit-conveyor = Convoyeur de sortie gauche
element-right-exit-conveyor = Convoyeur de sortie droit
element-turntable = Table tournante

# Ce que protège chaque contrainte (le commentaire de constraints.txt).
constraint-CSs1 = deux caisses entre C0 et C1 : arrêter le convoyeur d'entrée
constraint-CSs2 = caisse en bout de A1, table pas en position de chargement
constraint-CSs3 = caisse en bout de A1, table chargée
constraint-CSs4 = caisse en bout de A1 pendant qu'une autre entre sur la table
constraint-CSs5 = évacuation à droite seulement en position de déchargement
constraint-CSs6 = table chargée en position de chargement : rouleaux arrêtés
constraint-CSs7 = pas de rouleaux pendant la rotation
constraint-CSs8 = table chargée en position de déchargement : maintenir la rotation
constraint-CSs9 = caisse sortant à gauche : maintenir la rotation
constraint-CSs10 = caisse sortant à droite : maintenir la rotation
constraint-CSs11 = caisse entre C6 et C7 : maintenir la rotation
constraint-CSs12 = caisse en C7 : pas de rouleaux vers la gauche
constraint-CSs13 = pas de rotation d'une table vide
constraint-CSs14 = la rotation ne part que de la position de chargement
constraint-CSs15 = la rotation n'est relâchée qu'en position de déchargement
constraint-CSc1 = caisse poussée de A0 sur A1 arrêté
constraint-CSc2 = caisse poussée de A1 sur des rouleaux arrêtés

# A4 à l'arrêt (`off` dans plant.ron : une sortie à 0 qui fait bouger quelque chose).
off-A4 = la table tournante revient en position de chargement
