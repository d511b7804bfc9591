// Provides the shadow-map pass's fragment stage: depth only (the atlas is a depth attachment).
void main() {}
