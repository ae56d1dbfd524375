/* placeholder: replaced by the input-decoder work in progress */
int main(void) { return 1; }
