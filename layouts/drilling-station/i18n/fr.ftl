# Poste de perçage (thèse de Naifi, 1983, deuxième partie) : les textes de l'installation
# en français, lus par la console après les siens (`signal-<id>` : la description d'un
# signal). En anglais, la console montre les descriptions de plant.ron.

signal-h = Tête de perçage en haut (position de repos)
signal-b1 = Tête de perçage juste au-dessus de la pièce : fin de l'approche rapide
signal-b2 = Tête de perçage à la profondeur intermédiaire (point de débourrage)
signal-b3 = Tête de perçage à la profondeur de perçage finale
signal-DY = Bouton départ cycle
signal-DGV = Descente grande vitesse de la tête de perçage (approche)
signal-DPV = Descente petite vitesse de la tête de perçage (avance de perçage)
signal-MGV = Montée grande vitesse de la tête de perçage

# Les éléments de l'installation (`element` dans plant.ron : minuscules, espaces en
# tirets).
element-drill-head = Tête de perçage
element-panel = Pupitre

# Ce que protège chaque contrainte (le commentaire de constraints.txt).
constraint-CSd1 = descente grande vitesse et montée grande vitesse commandées ensemble
constraint-CSd2 = descente petite vitesse et montée grande vitesse commandées ensemble
constraint-CSd3 = pas de descente grande vitesse à partir de la fin de l'approche : le foret attaquerait la pièce à dix fois son avance
constraint-CSd4 = pas de descente à la profondeur finale ni au-delà : la tête irait heurter le montage

# Les sorties à l'arrêt (`off` dans plant.ron : ce que fait la machine quand la sortie
# est à 0).
off-DGV = la tête s'arrête où elle est ; la broche continue de tourner
off-DPV = la tête s'arrête où elle est ; la broche continue de tourner
off-MGV = la tête s'arrête où elle est ; la broche continue de tourner

# La bibliothèque d'erreurs de commande (programs/errors.ron).
variant-E01 = Approche rapide arrêtée sur le mauvais capteur (b2 au lieu de b1) : la descente grande vitesse continue après la fin de l'approche et enfonce le foret dans la pièce à 100 mm/s
variant-E02 = Montée grande vitesse écrite dans l'étape d'approche (action MGV dans X1 au lieu de X5) : la tête reçoit à la fois l'ordre de monter et celui de descendre
variant-E03 = Ordre de perçage mémorisé (S) au lieu de non mémorisé (N) dans la première étape de perçage X2 : DPV reste commandée pendant la remontée de débourrage
variant-E04 = Mauvaise sortie dans l'étape de retour (DPV, bobine 1, au lieu de MGV, bobine 2) : à la profondeur finale, la tête continue de descendre vers le montage
variant-E05 = Débourrage oublié : la première passe de perçage attend b3 au lieu de b2 ; le trou est percé à la profondeur finale en une passe, copeaux bourrés dans les goujures, puis repercé depuis b1
variant-E06 = Remontée de débourrage arrêtée en h au lieu de b1 : la tête revient en haut, puis refait l'approche de la pièce en petite vitesse (environ 10 s au lieu de 1 s)
variant-E07 = Capteur inversé dans la réceptivité de fin de cycle (/h au lieu de h) : la remontée s'arrête un cycle automate après son départ, la tête reste au fond du trou et DY ne lance plus de cycle (la tête n'est pas en h)

# Les observateurs (observers.ron) : ce qu'ils suivent, dans les explications.
observer-Pb1 = la tête de perçage est sous b1 (b1 exclu) : le foret est dans la pièce
observer-Pb3 = la tête de perçage est sous b3 (b3 exclu) : au-delà de la profondeur finale, à 8 mm au plus du montage

# Les tâches surveillées (tasks.ron) : les actions élémentaires, sujet de leurs alarmes.
task-N1 = N1, approche rapide : la tête quitte h en descente grande vitesse et atteint b1
task-N2 = N2, perçage de b1 à la profondeur intermédiaire b2 en descente petite vitesse
task-N3 = N3, montée grande vitesse de b2 à b1 : remontée de débourrage, et milieu du retour
task-N4 = N4, perçage de b2 à la profondeur finale b3 en descente petite vitesse
task-N5 = N5, montée grande vitesse de la profondeur finale b3 à b2
task-N6 = N6, montée grande vitesse de b1 au retour en haut h

# The components (components.ron) and the declared danger.
part-head = tête de perçage
part-start_button = bouton départ cycle
danger-fast_into_part = le foret entre dans la pièce en grande vitesse
