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
