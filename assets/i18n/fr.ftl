# Console Vigie, français. Chaque message a son jumeau dans en.ftl (un test le vérifie).
# Les textes d'une installation (descriptions des signaux) vont dans le dossier de
# l'installation, i18n/<langue>.ftl.

## Choix de la langue
lang-switch-hover = Langue de la console

## Barre d'outils
mode-production = Production
mode-maintenance = Maintenance
mode-training = Formation
mode-maintenance-needs-role = Modifier le programme demande le rôle maintenance : connectez-vous
sim-pause = Pause
sim-run = Marche
sim-step = Pas
sim-step-hover = Un cycle automate
sim-speed = Vitesse
plant-start = Départ cycle
plant-start-hover = Bouton DÉPART CYCLE de la machine
plant-stop = Arrêt
plant-stop-hover = Bouton ARRÊT de la machine

## État d'un coup d'œil
state-tripped = ARRÊT SÉCURITÉ
state-stopped = ARRÊTÉE
state-manual = MANUEL
state-degraded = DÉGRADÉ
state-idle = AU REPOS
state-running = EN PRODUCTION
state-tripped-hover = Le filtre de sécurité maintient les sorties dans leur état sûr
state-stopped-hover = Les diagnostiqueurs ont arrêté la machine : vérifiez-la, puis réarmez-les
state-manual-hover = L'opérateur pilote les sorties ; chaque commande est vérifiée
state-degraded-hover = Un capteur est lu par son estimation ou tenu pour suspect
state-idle-hover = Le programme est au repos : appuyez sur Départ cycle pour produire
state-running-hover = Le programme s'exécute
state-paused = SIMULATION EN PAUSE
state-unacknowledged = { $n ->
    [one] { $n } non acquittée
   *[other] { $n } non acquittées
}

## Panneau central
tab-synoptic = Synoptique
tab-trends = Courbes
tab-trends-hover = L'historique de n'importe quel signal, sur des minutes ou des jours

## Courbes
trends-range = Durée
trends-add = Ajouter un signal…
trends-full = { $n } signaux au plus
trends-filter = Filtrer
trends-remove-hover = Retirer { $signal } des courbes
trends-export = Exporter en CSV…
trends-export-hover = Les changements de ces signaux sur la durée, dans un fichier de votre choix
trends-no-history = Pas d'historique : la console tourne sans dossier de données (le journal n'est qu'en mémoire).
trends-empty = Ajoutez un signal pour voir son historique.
trends-legend = Chaque ligne est un signal, haut à 1 ; une barre pleine est un signal qui a changé plus vite que l'écran ne peut le montrer (zoomez). « .cmd » est la sortie commandée par le programme, sans lui la sortie appliquée.
trends-now = maintenant
