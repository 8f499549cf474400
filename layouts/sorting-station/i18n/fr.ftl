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
signal-A0_fb = Contacteur de A0 fermé (contact miroir)
signal-A1_fb = Contacteur de A1 fermé (contact miroir)
signal-A2_fb = Contacteur de A2 fermé (contact miroir)
signal-A3_fb = Contacteur de A3 fermé (contact miroir)
signal-A4_fb = Distributeur de A4 commuté (contrôle de tiroir)
signal-A5_fb = Contacteur de A5 fermé (contact miroir)
signal-A6_fb = Contacteur de A6 fermé (contact miroir)
signal-KM0_fb = KM0 fermé (contact miroir)
signal-YV0_fb = YV0 ouvert sur l'alimentation (contrôle de tiroir)
signal-KM0 = Contacteur de sécurité sur l'alimentation des convoyeurs et des rouleaux
signal-YV0 = Distributeur de sécurité sur l'air de la table tournante

# Les éléments de l'installation (`element` dans plant.ron : minuscules, espaces en
# tirets).
element-entry-conveyor = Convoyeur d'entrée
element-intermediate-conveyor = Convoyeur intermédiaire
element-left-exit-conveyor = Convoyeur de sortie gauche
element-right-exit-conveyor = Convoyeur de sortie droit
element-turntable = Table tournante
element-safety = Sécurité

# Les parties de layout.ron (`id`), pour dire où une caisse est endommagée.
part-entry = Convoyeur d'entrée
part-intermediate = Convoyeur intermédiaire
part-left_exit = Convoyeur de sortie gauche
part-right_exit = Convoyeur de sortie droit
part-table = Table tournante

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
constraint-CSk1 = A0 soudé : couper KM0
constraint-CSk2 = A0 ne se ferme pas : couper KM0
constraint-CSk3 = A1 soudé : couper KM0
constraint-CSk4 = A1 ne se ferme pas : couper KM0
constraint-CSk5 = A2 soudé : couper KM0
constraint-CSk6 = A2 ne se ferme pas : couper KM0
constraint-CSk7 = A3 soudé : couper KM0
constraint-CSk8 = A3 ne se ferme pas : couper KM0
constraint-CSk9 = A4 collé : couper YV0
constraint-CSk10 = A4 ne commute pas : couper YV0
constraint-CSk11 = A5 soudé : couper KM0
constraint-CSk12 = A5 ne se ferme pas : couper KM0
constraint-CSk13 = A6 soudé : couper KM0
constraint-CSk14 = A6 ne se ferme pas : couper KM0
constraint-CSk15 = KM0 ne se ferme pas : toutes les sorties à l'arrêt jusqu'à la réparation
constraint-CSk16 = YV0 ne s'ouvre pas : toutes les sorties à l'arrêt jusqu'à la réparation

# A4 à l'arrêt (`off` dans plant.ron : une sortie à 0 qui fait bouger quelque chose).
off-A4 = la table tournante revient en position de chargement
off-KM0 = tous les convoyeurs et les rouleaux s'arrêtent, quel que soit leur propre contacteur
off-YV0 = la table tournante reste où elle est, quel que soit son distributeur

# Les scénarios (`scenario-<nom du fichier>` : son titre dans la ligne d'état).
scenario-a1-dead-belt = A1 en panne sous une caisse poussée
scenario-a4-stuck-on = A4 bloquée EN MARCHE (distributeur de la table)
scenario-c4-stuck-degraded = C4 bloqué à 0, mode dégradé
scenario-c6-phantom = C6 fantôme en position de chargement
scenario-cs10-paper = CSs10 : A4 relâchée pendant que la caisse sort à droite
scenario-learn-mixed = Tailles mélangées, alimentation chargée (trace d'apprentissage)
scenario-reference-hour = Programme de référence, une heure de production
scenario-table-blocked = Table tournante bloquée entre les positions
scenario-tasks-hour = Une heure avec des pauses de l'opérateur

# La bibliothèque d'erreurs de commande (programs/errors.ron).
variant-E01 = Rotation relâchée sur le front montant de C7 au lieu de son front descendant : la caisse sort encore à droite (l'exemple de l'article)
variant-E02 = Évacuation à droite jugée finie quand la caisse quitte le centre de la table (FE(C6)) au lieu de FE(C7) : A4 relâchée avec la caisse entre C6 et C7
variant-E03 = Évacuation à gauche jugée finie sur FE(C6) au lieu de FE(C8) : A4 relâchée alors que la caisse est encore en C8
variant-E04 = A4 non maintenue dans l'étape d'évacuation à droite (actionneur monostable traité comme bistable) : la table chargée quitte la position de déchargement
variant-E05 = Évacuation à droite lancée dès que la table quitte la position de chargement (/C4 au lieu de C5) : A3 tourne pendant la rotation
variant-E06 = Évacuation à gauche lancée dès que la table quitte la position de chargement (/C4 au lieu de C5) : A2 tourne pendant la rotation
variant-E07 = Rouleaux mémorisés (S) au lieu de non mémorisés (N) dans l'étape de centrage : A2 tourne encore quand la table chargée est en C4
variant-E08 = Capteur de présence inversé dans la réceptivité de rotation (/C6 au lieu de C6) : la table vide se met à tourner
variant-E09 = Ordre de rotation impulsionnel (P) au lieu de maintenu (N) dans l'étape de rotation à droite : A4 retombe entre les positions
variant-E10 = Ordre de rotation limité à 1 s (L) dans l'étape de rotation à gauche, plus court que la rotation de 2,9 s : A4 retombe entre les positions
variant-E11 = Convoyeur intermédiaire non démarré pendant la poussée de la caisse depuis C0 (X11 absent de l'équation de A1)
variant-E12 = Rouleaux non démarrés pendant que la caisse est tirée de A1 (action A2 absente de X21) : la caisse est poussée sur des rouleaux arrêtés
variant-E13 = Convoyeur intermédiaire jamais arrêté en C3 (le facteur d'arrêt manque dans l'équation de A1)
variant-E14 = La poussée finit quand la caisse a passé C1 (FE(C1)) au lieu de C0 : A0 continue d'alimenter et la caisse suivante atteint C0 pendant que la première couvre encore C1



# Les observateurs (observers.ron) : ce qu'ils suivent, dans les explications.
observer-P36 = une caisse entre C3 et C6 (exclus) : elle quitte le convoyeur intermédiaire pour la table
observer-P67 = une caisse entre C6 et C7 (exclus) : elle quitte la table vers la droite
observer-2P = deux caisses entre C0 et C1, et non une seule à cheval sur les deux
# Les tâches surveillées (tasks.ron) : le sujet de leurs alarmes.
task-entry = Caisse poussée du convoyeur d'entrée sur le convoyeur intermédiaire (de C0 à C1)
task-intermediate = Caisse portée par le convoyeur intermédiaire de C1 à son bout C3
task-load_table = Caisse passant de C3 sur la table (rouleaux A2) jusqu'à C6
task-turn_out = Rotation de la table de la position de chargement (C4) à celle de déchargement (C5)
task-turn_back = Retour de la table de la position de déchargement (C5) à celle de chargement (C4)
task-evac_left = Caisse portée par le convoyeur de sortie gauche A5 de C8 à C10
task-evac_right = Caisse portée par le convoyeur de sortie droit A6 de C7 à C9
# Les exercices de défaut de la partie opérative (exercises.ron).
exercise-P01 = La cellule C3 en bout du convoyeur intermédiaire est bloquée à 1 : le filtre voit une caisse à la jonction alors qu'il n'y en a pas
exercise-P02 = Le distributeur de rotation A4 est bloqué fermé : la table ne quitte jamais la position de chargement avec sa caisse
exercise-P03 = La cellule de la table C6 est bloquée à 1 : la table croit porter une caisse alors qu'elle est vide
exercise-P04 = La table tournante est bloquée mécaniquement en position de déchargement : A4 relâché, elle ne revient pas en C4
exercise-P05 = Le moteur des rouleaux de la table A2 ne tourne pas (contacteur mort) : la caisse n'est pas tirée sur la table
