package org.pocketbot.android

/** Placeholder until the Android app lands. */
internal const val MODULE_NAME: String = "pocketbot-android-app"
